"""Renders a Mitsuba 3 scene exported by voxgi (`voxgi export-mitsuba`) to a linear EXR.

Run through `tools/reference`, which provides the virtual environment. See
assets/references/README.md for the settings of the committed references.
"""

import argparse
import os
import sys
import time


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog="tools/reference",
        description="Render a voxgi Mitsuba export (a directory holding scene.xml, or the "
        "XML itself) to a linear RGB OpenEXR file.",
    )
    p.add_argument("scene", help="export directory (with scene.xml) or an XML file")
    p.add_argument("out", help="output .exr path")
    p.add_argument("--spp", type=int, default=None,
                   help="samples per pixel (default: the XML's, 256)")
    p.add_argument("--max-depth", type=int, default=None,
                   help="path segments from the camera: 2 = direct light only, 3 = one "
                   "indirect bounce, -1 = unbounded (default: the XML's, 64)")
    p.add_argument("--seed", type=int, default=0, help="sampler seed (default 0)")
    p.add_argument("--variant", default="scalar_rgb",
                   help="Mitsuba variant (default scalar_rgb; llvm_ad_rgb needs a libLLVM that "
                   "Dr.Jit supports, the system LLVM 15 crashes it)")
    p.add_argument("--float32", action="store_true",
                   help="write 32-bit float channels instead of half floats")
    p.add_argument("--preview", default=None, metavar="PNG",
                   help="also write a tone-mapped sRGB PNG (exposure --preview-exposure)")
    p.add_argument("--preview-exposure", type=float, default=1.0,
                   help="linear scale applied before clamping for --preview")
    p.add_argument("--pass-spp", type=int, default=64,
                   help="samples per pass (default 64); progress and the noise estimate are "
                   "reported per pass")
    return p.parse_args(argv)


def pick_variant(mi, wanted):
    if wanted not in mi.variants():
        sys.exit(f"tools/reference: Mitsuba has no variant {wanted}; available: "
                 f"{', '.join(mi.variants())}")
    try:
        mi.set_variant(wanted)
    except Exception as e:  # noqa: BLE001 - report any failure the same way
        sys.exit(f"tools/reference: cannot use variant {wanted} ({e}); try --variant scalar_rgb")
    return wanted


def relmse_main(argv):
    if len(argv) != 2:
        sys.exit("usage: tools/reference --relmse TEST.exr REFERENCE.exr")
    import mitsuba as mi
    import numpy as np
    mi.set_variant("scalar_rgb")
    test, ref = (np.array(mi.Bitmap(p), dtype=np.float64)[:, :, :3] for p in argv)
    if test.shape != ref.shape:
        sys.exit(f"tools/reference: sizes differ: {test.shape} vs {ref.shape}")
    # voxgi's eval::metrics definition: mean over pixels and channels, epsilon 1e-2.
    print(f"relMSE {np.mean((test - ref) ** 2 / (ref * ref + 1e-2)):.4e}")


def main(argv):
    if argv[:1] == ["--relmse"]:
        return relmse_main(argv[1:])
    args = parse_args(argv)
    import mitsuba as mi
    import numpy as np

    xml = args.scene
    if os.path.isdir(xml):
        xml = os.path.join(xml, "scene.xml")
    if not os.path.isfile(xml):
        sys.exit(f"tools/reference: {xml} does not exist: export the scene first "
                 f"(tools/voxgi export-mitsuba SCENE -o DIR)")

    variant = pick_variant(mi, args.variant)
    params = {"seed": args.seed}
    if args.spp is not None:
        params["spp"] = args.spp
    if args.max_depth is not None:
        params["max_depth"] = args.max_depth

    t0 = time.time()
    scene = mi.load_file(xml, **params)
    spp = scene.sensors()[0].sampler().sample_count()
    print(f"tools/reference: Mitsuba {mi.__version__} {variant}, {xml}, spp {spp}, "
          f"max_depth {params.get('max_depth', 'from the XML')}, seed {args.seed}", flush=True)

    # Render in passes of --pass-spp samples with distinct seeds and average them (equal to
    # one render with the summed sample count: box filter, equal weights). Even and odd passes
    # form two independent half renders A and B; their difference measures the noise.
    passes = max(1, -(-spp // max(1, args.pass_spp)))
    if spp >= 2:
        passes = max(passes, 2)
    per_pass = [spp // passes + (1 if i < spp % passes else 0) for i in range(passes)]
    halves = [np.zeros(1), np.zeros(1)]
    counts = [0, 0]
    for i, n in enumerate(per_pass):
        img = np.array(mi.render(scene, spp=n, seed=args.seed * 1_000_003 + i), dtype=np.float64)
        halves[i % 2] = halves[i % 2] + img[:, :, :3] * n
        counts[i % 2] += n
        done = sum(per_pass[: i + 1])
        print(f"tools/reference: {done}/{spp} spp, {time.time() - t0:.1f} s", flush=True)
    img = ((halves[0] + halves[1]) / spp).astype(np.float32)
    if counts[1] > 0:
        a, b = halves[0] / counts[0], halves[1] / counts[1]
        m = 0.5 * (a + b)
        # relMSE as voxgi's eval::metrics (epsilon 1e-2), mean over pixels and channels.
        rel = float(np.mean((a - b) ** 2 / (m * m + 1e-2)))
        # Noise variance falls as 1/spp: rel = s2 (1/na + 1/nb) for a per-sample s2.
        s2 = rel / (1.0 / counts[0] + 1.0 / counts[1])
        print(f"tools/reference: noise: relMSE between the two halves ({counts[0]} vs "
              f"{counts[1]} spp) = {rel:.3e}; two {spp}-spp renders with different seeds "
              f"would differ by about {2 * s2 / spp:.3e}; this image's own relMSE against "
              f"the converged image is about {s2 / spp:.3e}", flush=True)

    if not np.all(np.isfinite(img)):
        sys.exit("tools/reference: the render holds NaN or infinite values; not writing it")
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    bmp = mi.Bitmap(img, pixel_format=mi.Bitmap.PixelFormat.RGB)
    if not args.float32:
        # Half floats keep 11 significant bits (relMSE against float32 ~1e-8, far below the
        # noise) and let the lossless PIZ compression Mitsuba uses cut the file to a third.
        bmp = bmp.convert(component_format=mi.Struct.Type.Float16)
    bmp.write(args.out)
    print(f"tools/reference: wrote {args.out} ({time.time() - t0:.1f} s)", flush=True)

    if args.preview:
        ldr = np.clip(img * args.preview_exposure, 0.0, 1.0)
        ldr = np.where(ldr <= 0.0031308, 12.92 * ldr, 1.055 * np.power(ldr, 1 / 2.4) - 0.055)
        out = mi.Bitmap((ldr * 255.0 + 0.5).astype(np.uint8),
                        pixel_format=mi.Bitmap.PixelFormat.RGB)
        out.write(args.preview)
        print(f"tools/reference: wrote {args.preview}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
