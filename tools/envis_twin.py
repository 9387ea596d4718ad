#!/usr/bin/env python3
"""CPU twin of the environment map's importance sampling (numpy only): the oracle that
`src/scene/environment.rs` (the CDF) and `glsl/include/environment_sampling.glsl` (sampling and
density) follow, step by step.

Checks, with a Monte Carlo estimate, that a white Lambert floor (normal +Y) under an
equirectangular map gets the irradiance E = integral of L cos(theta) over the upper hemisphere,
computed independently by quadrature over sub-texels of the bilinear lookup:

  * a map black but for a 2 x 2-texel sun, and a smooth map (a sky gradient);
  * three estimators: cosine sampling alone, the map's density alone, and both combined by
    the balance heuristic (Veach 1997, section 9.2.2; every sample weighs f / (n_e p_e + n_c p_c)).

Run: python3 tools/envis_twin.py [--samples N] [--seed S]. Exits non-zero if an estimate is
more than 5 standard errors from the quadrature.
"""

import argparse
import sys

import numpy as np

PI = np.pi


# --- The convention, in one place (environment.glsl's environment_uv and its inverse) -------
# A world direction d is turned by -rotation about +Y into the map's frame, where
# u = atan2(x, -z) / 2pi and v = acos(y) / pi (u = 0 along -Z, 1/4 along +X, the top row up).
def direction_to_uv(d, rotation):
    s, c = np.sin(rotation), np.cos(rotation)
    lx = c * d[..., 0] - s * d[..., 2]
    ly = d[..., 1]
    lz = s * d[..., 0] + c * d[..., 2]
    u = np.arctan2(lx, -lz) / (2 * PI)
    v = np.arccos(np.clip(ly, -1, 1)) / PI
    return u - np.floor(u), v


def uv_to_direction(u, v, rotation):
    phi, theta = 2 * PI * u, PI * v
    lx, ly, lz = np.sin(theta) * np.sin(phi), np.cos(theta), -np.sin(theta) * np.cos(phi)
    s, c = np.sin(rotation), np.cos(rotation)
    return np.stack([c * lx + s * lz, ly, -s * lx + c * lz], axis=-1)


# --- The lookup (environment_radiance): bilinear, repeating in u, v within the rows' centres --
def radiance(img, d, rotation):
    h, w, _ = img.shape
    u, v = direction_to_uv(d, rotation)
    v = np.clip(v, 0.5 / h, 1 - 0.5 / h)
    x = u * w - 0.5
    y = v * h - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    fx = (x - x0)[..., None]
    fy = (y - y0)[..., None]
    x0 = x0.astype(int) % w
    x1 = (x0 + 1) % w
    y0 = np.clip(y0.astype(int), 0, h - 1)
    y1 = np.clip(y0 + 1, 0, h - 1)
    top = img[y0, x0] * (1 - fx) + img[y0, x1] * fx
    bottom = img[y1, x0] * (1 - fx) + img[y1, x1] * fx
    return top * (1 - fy) + bottom * fy


def luminance(rgb):
    return 0.2126 * rgb[..., 0] + 0.7152 * rgb[..., 1] + 0.0722 * rgb[..., 2]


# --- The CDF (scene::environment::EnvironmentCdf::new) ------------------------------------
def texel_weights(img):
    """Each texel's weight: the luminance smoothed by [1/8, 3/4, 1/8] in u (repeating) and in v
    (clamped), which is the integral of the bilinear lookup over the texel in each axis, so
    every texel the lookup spreads a bright texel into has weight, times sin(theta) at the
    row's centre (the row's solid angle per texel, dw = 2 pi^2 sin(theta) du dv)."""
    h, w, _ = img.shape
    y = luminance(img)
    y = 0.75 * y + 0.125 * (np.roll(y, 1, axis=1) + np.roll(y, -1, axis=1))
    up = np.concatenate([y[:1], y[:-1]], axis=0)
    down = np.concatenate([y[1:], y[-1:]], axis=0)
    y = 0.75 * y + 0.125 * (up + down)
    theta = PI * (np.arange(h) + 0.5) / h
    return y * np.sin(theta)[:, None]


def build_cdf(img):
    """The marginal CDF over rows (h + 1 values, 0 first, 1 last) and each row's conditional
    CDF over its columns (h x (w + 1)), in float32 as the GPU reads them. A black row's
    conditional is uniform (never picked: its marginal interval is empty)."""
    h, w, _ = img.shape
    wt = texel_weights(img).astype(np.float64)
    rows = wt.sum(axis=1)
    total = rows.sum()
    if total <= 0:
        return None
    marginal = np.concatenate([[0.0], np.cumsum(rows) / total])
    marginal[-1] = 1.0
    cond = np.empty((h, w + 1))
    for j in range(h):
        if rows[j] > 0:
            cond[j] = np.concatenate([[0.0], np.cumsum(wt[j]) / rows[j]])
        else:
            cond[j] = np.linspace(0, 1, w + 1)
        cond[j, -1] = 1.0
    return marginal.astype(np.float32), cond.astype(np.float32)


MAP_SHARE_SOLID_ANGLE = 0.01
MAP_SHARE_GATE = 0.5
MAP_SHARE_MAX = 0.5


def map_share(img):
    """alpha (EnvironmentCdf::map_share): s, the share of the power (the CDF's texel weights)
    in the brightest MAP_SHARE_SOLID_ANGLE of the sphere, texels ordered by luminance and the
    last counted in part; alpha = MAP_SHARE_MAX where s >= MAP_SHARE_GATE, else 0. (For a
    two-level map the mixture's second moment s^2 / (a + alpha (1 - a)) + (1 - s)^2 /
    ((1 - a)(1 - alpha)) is least at alpha = (s - a) / (1 - a), above the cap once s > 0.505;
    below the gate stratified cosine samples do better than that model says.)"""
    h, w, _ = img.shape
    power = texel_weights(img).astype(np.float64).ravel()
    sin = np.repeat(np.sin(PI * (np.arange(h) + 0.5) / h), w)
    if power.sum() <= 0:
        return 0.0
    order = np.argsort(-(power / sin), kind="stable")
    p = power[order] / power.sum()
    omega = sin[order] / sin.sum()
    a = MAP_SHARE_SOLID_ANGLE
    before = np.concatenate([[0.0], np.cumsum(omega)[:-1]])
    take = np.clip((a - before) / omega, 0.0, 1.0)
    s = (p * take).sum()
    return MAP_SHARE_MAX if s >= MAP_SHARE_GATE else 0.0


def find_interval(cdf, u):
    """The i with cdf[i] <= u < cdf[i + 1] (the GPU's binary search), skipping empty ones."""
    i = np.searchsorted(cdf, u, side="right") - 1
    return np.clip(i, 0, len(cdf) - 2)


def texel_probability(cdf, i, j):
    marginal, cond = cdf
    return (marginal[j + 1] - marginal[j]).astype(np.float64) * (
        cond[j, i + 1] - cond[j, i]
    ).astype(np.float64)


def sample(cdf, shape_hw, u1, u2, rotation):
    """env_sample: a row by the marginal, a column by the row's conditional, then a point
    uniformly within the texel (the rescaled u, so stratification survives). Returns the
    direction and its density per solid angle."""
    marginal, cond = cdf
    h, w = shape_hw
    j = find_interval(marginal, u2)
    fy = (u2 - marginal[j]) / np.maximum(marginal[j + 1] - marginal[j], 1e-30)
    i = find_interval_rows(cond, j, u1)
    fx = (u1 - cond[j, i]) / np.maximum(cond[j, i + 1] - cond[j, i], 1e-30)
    u = (i + np.clip(fx, 0, 1)) / w
    v = (j + np.clip(fy, 0, 1)) / h
    d = uv_to_direction(u, v, rotation)
    return d, pdf_at(cdf, shape_hw, u, v, i, j)


def find_interval_rows(cond, j, u):
    """find_interval in row j's conditional CDF, per sample (vectorized binary search)."""
    w = cond.shape[1] - 1
    lo = np.zeros_like(j)
    hi = np.full_like(j, w - 1)
    while np.any(lo < hi):
        mid = (lo + hi + 1) // 2
        go = cond[j, mid] <= u
        lo = np.where(go & (lo < hi), mid, lo)
        hi = np.where(~go & (lo < hi), mid - 1, hi)
    return lo


def pdf_at(cdf, shape_hw, u, v, i, j):
    """Density per solid angle of a point (u, v) in texel (i, j): p_texel W H / (2 pi^2 sin(theta)),
    theta at the point itself (the density is uniform in (u, v) within the texel)."""
    h, w = shape_hw
    s = np.sin(PI * v)
    p = texel_probability(cdf, i, j) * (w * h) / (2 * PI * PI * np.maximum(s, 1e-30))
    return np.where(s > 0, p, 0.0)


def env_pdf(cdf, shape_hw, d, rotation):
    """env_pdf(dir): the texel the direction falls in (nearest, not the bilinear footprint:
    the sampled texel is the one whose interval the point lies in)."""
    h, w = shape_hw
    u, v = direction_to_uv(d, rotation)
    i = np.minimum((u * w).astype(int), w - 1)
    j = np.minimum((v * h).astype(int), h - 1)
    return pdf_at(cdf, shape_hw, u, v, i, j)


# --- Cosine sampling (material_lobe.glsl's diffuse lobe about +Y) -------------------------
def cosine_sample(u1, u2):
    r = np.sqrt(u1)
    phi = 2 * PI * u2
    return np.stack([r * np.cos(phi), np.sqrt(np.maximum(1 - u1, 0)), r * np.sin(phi)], axis=-1)


# --- The reference: E by quadrature over sub-texels of the bilinear lookup ----------------
def irradiance_quadrature(img, rotation, sub=8):
    h, w, _ = img.shape
    uu = (np.arange(w * sub) + 0.5) / (w * sub)
    vv = (np.arange(h * sub // 2) + 0.5) / (h * sub)  # the upper hemisphere: v < 1/2
    U, V = np.meshgrid(uu, vv)
    d = uv_to_direction(U, V, rotation)
    l = radiance(img, d, rotation)
    dw = 2 * PI * PI * np.sin(PI * V) / (w * sub * h * sub)
    cos = np.maximum(d[..., 1], 0)
    return (l * (cos * dw)[..., None]).sum(axis=(0, 1))


def estimate(img, cdf, rotation, n, rng, strategy):
    """Per-sample estimates of E (mean and standard error): `cosine`, `env` or `mis` (n_e = n_c
    = n, balance heuristic: each sample of either strategy weighs L cos / (p_e + p_c), and the
    pair's sum is one estimate)."""
    h, w, _ = img.shape
    shape = (h, w)
    out = np.zeros((n, 3))
    if strategy in ("cosine", "mis"):
        d = cosine_sample(rng.random(n), rng.random(n))
        cos = d[:, 1]
        pc = cos / PI
        pe = env_pdf(cdf, shape, d, rotation) if strategy == "mis" else 0.0
        out += radiance(img, d, rotation) * (cos / (pc + pe))[:, None]
    if strategy in ("env", "mis"):
        d, pe = sample(cdf, shape, rng.random(n).astype(np.float32), rng.random(n).astype(np.float32), rotation)
        cos = np.maximum(d[:, 1], 0)
        pc = cos / PI if strategy == "mis" else 0.0
        ok = pe > 0
        f = np.where(ok, cos / np.where(ok, pe + pc, 1.0), 0.0)
        out += radiance(img, d, rotation) * f[:, None]
    return out.mean(axis=0), out.std(axis=0) / np.sqrt(n)


def estimate_mixture(img, cdf, rotation, k, batches, rng):
    """direct_emitters' estimator: of K directions, n_e = round(alpha K) from the map and the
    rest cosine-distributed, every sample weighing L cos / (n_e p_e + n_c p_c) and their sum
    one estimate (the balance heuristic's multi-sample form, Veach 1997, section 9.2.2; with
    n_e = 0 it is cosine sampling alone). Returns the mean and standard error over `batches`
    such estimates, and alpha."""
    h, w, _ = img.shape
    shape = (h, w)
    alpha = map_share(img)
    ne = int(np.floor(alpha * k + 0.5))
    nc = max(k - ne, 1)
    out = np.zeros((batches, 3))
    d = cosine_sample(rng.random(batches * nc), rng.random(batches * nc))
    cos = d[:, 1]
    pe = env_pdf(cdf, shape, d, rotation) if ne > 0 else 0.0
    f = radiance(img, d, rotation) * (cos / (nc * cos / PI + ne * pe))[:, None]
    out += f.reshape(batches, nc, 3).sum(axis=1)
    if ne > 0:
        u1 = rng.random(batches * ne).astype(np.float32)
        u2 = rng.random(batches * ne).astype(np.float32)
        d, pe = sample(cdf, shape, u1, u2, rotation)
        cos = np.maximum(d[:, 1], 0)
        ok = pe > 0
        g = np.where(ok, cos / np.where(ok, ne * pe + nc * cos / PI, 1.0), 0.0)
        out += (radiance(img, d, rotation) * g[:, None]).reshape(batches, ne, 3).sum(axis=1)
    return out.mean(axis=0), out.std(axis=0) / np.sqrt(batches), alpha


def sun_map(w=64, h=32, sun=(40, 9), radiance_sun=1000.0, sky=0.0):
    img = np.full((h, w, 3), sky, dtype=np.float32)
    x, y = sun
    img[y : y + 2, x : x + 2] = radiance_sun
    return img


def smooth_map(w=64, h=32):
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(w) + 0.5) / w
    V, U = np.meshgrid(v, u, indexing="ij")
    base = 0.5 + 1.5 * np.cos(PI * V).clip(0) + 0.3 * np.sin(2 * PI * U)
    return np.stack([base, 0.9 * base, 1.2 * base], axis=-1).astype(np.float32)


def write_hdr(path, img):
    """A Radiance .hdr (RGBE, flat scanlines, top row first): exact for the sun map's values
    (1000 = 250/256 * 2^10, 0.125 = 128/256 * 2^-2)."""
    h, w, _ = img.shape
    m = img.max(axis=-1)
    e = np.where(m > 0, np.floor(np.log2(np.maximum(m, 1e-38))) + 1, 0)
    scale = np.where(m > 0, 256.0 / np.exp2(e), 0.0)
    rgbe = np.zeros((h, w, 4), np.uint8)
    rgbe[..., :3] = np.clip(np.floor(img * scale[..., None]), 0, 255).astype(np.uint8)
    rgbe[..., 3] = np.where(m > 0, e + 128, 0).astype(np.uint8)
    with open(path, "wb") as f:
        f.write(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n" + f"-Y {h} +X {w}\n".encode())
        f.write(rgbe.tobytes())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--samples", type=int, default=200_000)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument(
        "--write-sun-map",
        metavar="PATH",
        help="write the measurement scene's map (64 x 32, a 2 x 2-texel sun of 1000 over a sky "
        "of 0.125) as Radiance .hdr and exit",
    )
    args = ap.parse_args()
    if args.write_sun_map:
        write_hdr(args.write_sun_map, sun_map(sky=0.125))
        return
    rng = np.random.default_rng(args.seed)
    ok = True
    for name, img, rotation in [
        ("sun 2x2", sun_map(), 0.0),
        ("sun 2x2, rotated 30 deg", sun_map(), np.radians(30.0)),
        ("smooth", smooth_map(), 0.0),
        ("constant", np.ones((32, 64, 3), np.float32), 0.0),
    ]:
        cdf = build_cdf(img)
        ref = irradiance_quadrature(img, rotation)
        print(f"{name}: quadrature E = {ref[0]:.6g} (pi L for a constant: {PI:.6g})")
        for strategy in ("cosine", "env", "mis"):
            mean, se = estimate(img, cdf, rotation, args.samples, rng, strategy)
            # The quadrature's own error (sub-texel midpoints) is about 1e-4 relative.
            z = np.abs(mean[0] - ref[0]) / max(se[0], 1e-4 * ref[0])
            flag = "ok" if z < 5 else "BIASED"
            if flag != "ok":
                ok = False
            print(
                f"  {strategy:6s} E = {mean[0]:.6g} +- {se[0]:.3g}  (ratio {mean[0] / ref[0]:.4f},"
                f" {z:.1f} sigma, relative std per sample {se[0] * np.sqrt(args.samples) / ref[0]:.3g}) {flag}"
            )
    # The default estimator: alpha from the map (0 for the constant, the cap for the sun), the
    # mixture unbiased at K = 4, 16, 64, and its error per estimate against cosine sampling's
    # at the same K.
    print("the mixture at alpha = map_share (direct_emitters' default):")
    for name, img, rotation in [
        ("sun 2x2 on a sky of 0.125", sun_map(sky=0.125), 0.0),
        ("smooth", smooth_map(), 0.0),
        ("constant", np.ones((32, 64, 3), np.float32), 0.0),
    ]:
        cdf = build_cdf(img)
        ref = irradiance_quadrature(img, rotation)
        for k in (4, 16, 64):
            batches = max(args.samples // k, 1000)
            mean, se, alpha = estimate_mixture(img, cdf, rotation, k, batches, rng)
            z = np.abs(mean[0] - ref[0]) / max(se[0], 1e-4 * ref[0])
            flag = "ok" if z < 5 else "BIASED"
            ok &= flag == "ok"
            ne = int(np.floor(alpha * k + 0.5))
            # Cosine sampling's standard deviation per sample, over the K of one estimate.
            cos_se = estimate(img, cdf, rotation, batches * k, rng, "cosine")[1][0]
            rel = se[0] * np.sqrt(batches) / ref[0]
            rel_cos = cos_se * np.sqrt(batches * k) / np.sqrt(k) / ref[0]
            print(
                f"  {name}, K = {k}: alpha {alpha:.4f}, n_e {ne}; E ratio {mean[0] / ref[0]:.4f}"
                f" ({z:.1f} sigma) {flag}; relative std per estimate {rel:.3g}"
                f" (cosine alone {rel_cos:.3g})"
            )
    # The density integrates to 1 over the sphere (a check of the sin(theta) and W H / 2 pi^2).
    img = sun_map()
    cdf = build_cdf(img)
    d = rng.normal(size=(400_000, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    integral = (env_pdf(cdf, img.shape[:2], d, 0.3) * 4 * PI).mean()
    print(f"integral of env_pdf over the sphere (uniform MC): {integral:.4f}")
    ok &= abs(integral - 1) < 0.05
    sys.exit(0 if ok else 1)


if __name__ == "__main__":
    main()
