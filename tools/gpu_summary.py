#!/usr/bin/env python3
"""Markdown summary of a `tools/gpu-run` results folder (stdout).

    python3 tools/gpu_summary.py RESULTS_DIR

Reads env.txt, steps.tsv and the steps' outputs (profile JSON, bench JSON, the sweep's CSV)
and prints: the device, every step's status, the validation pass, per scene the frame time
of every method and the per-pass table, the targets of the GPU issue against what was
measured, and the benches. Standard library only (it runs on the device machine too).
"""

import csv
import glob
import json
import os
import sys

# The profiled scenes, longest name first (step names are profile_<scene>_<config>).
SCENES = ["cornell_bunny", "cornell", "atrium", "sponza"]

# The targets at 1920x1080 (scene, configuration, ms): the per-pass table says which pass
# misses one.
TARGETS = [
    ("cornell", "none", 2.0, "direct frame"),
    ("cornell", "ssgi", 4.0, "fastest GI rung (ssgi)"),
    ("cornell", "hemisphere-4", 8.0, "hemisphere, 4 rays"),
    ("cornell", "pathtrace-1x2", 12.0, "path tracer, 1 ray, 2 bounces"),
    ("cornell", "vpl-16", 8.0, "VPLs, 16 per pixel"),
    ("atrium", "none", 6.0, "atrium direct frame"),
]


def read(path):
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return f.read()
    except OSError:
        return ""


def load_json(path):
    text = read(path)
    if not text.strip():
        return None
    try:
        return json.loads(text)
    except json.JSONDecodeError:
        return None


def steps(res):
    rows = []
    for line in read(os.path.join(res, "steps.tsv")).splitlines():
        parts = line.split("\t")
        if len(parts) == 3:
            rows.append(tuple(parts))
    return rows


def first_error(res, name):
    lines = [l for l in read(os.path.join(res, name + ".err")).splitlines() if l.strip()]
    for l in lines:
        if "error" in l.lower() or "validation" in l.lower():
            return l.strip()[:200]
    return lines[-1].strip()[:200] if lines else ""


def fmt_ms(v):
    if v is None:
        return "—"
    return f"{v:.3f}" if v < 10 else f"{v:.1f}"


def main():
    res = sys.argv[1]
    out = []
    env = dict(
        l.split("=", 1) for l in read(os.path.join(res, "env.txt")).splitlines() if "=" in l
    )
    status = {name: (rc, secs) for name, rc, secs in steps(res)}

    profiles = {}
    for name in status:
        if name.startswith("profile_"):
            data = load_json(os.path.join(res, name + ".out"))
            if data:
                rest = name[len("profile_"):]
                scene = next((s for s in SCENES if rest.startswith(s + "_")), rest.split("_")[0])
                profiles[(scene, rest[len(scene) + 1:])] = data
    device = next((p["device"] for p in profiles.values() if "device" in p), None)

    out.append(f"# GPU run: {device or env.get('gpu', 'unknown device')}")
    out.append("")
    out.append(
        f"`tools/gpu-run {'device' if env.get('mode') == 'device' else '--local'}` on "
        f"{env.get('date', '?')}, commit {env.get('commit', '?')}; "
        f"GPU {env.get('gpu', 'none reported by nvidia-smi')}; {env.get('cpus', '?')} CPUs; "
        f"{env.get('uname', '')}."
    )
    out.append("")
    out.append("## Devices")
    out.append("")
    out.append("```text")
    out.append(read(os.path.join(res, "devices.out")).rstrip() or "(no output)")
    out.append("```")
    out.append("")

    out.append("## Steps")
    out.append("")
    out.append("| step | exit | s | first error |")
    out.append("|---|---|---|---|")
    for name, (rc, secs) in status.items():
        err = "" if rc in ("0", "skipped") else first_error(res, name).replace("|", "\\|")
        out.append(f"| {name} | {rc} | {secs} | {err} |")
    out.append("")

    val = [(n, rc) for n, (rc, _) in status.items() if n.startswith("validate_")]
    if val:
        ok = sum(1 for _, rc in val if rc == "0")
        out.append("## Validation")
        out.append("")
        out.append(
            f"{ok} of {len(val)} renders with `--validate` (Khronos validation and "
            "synchronization validation; any message fails the render) exited cleanly."
        )
        out.append("")

    if profiles:
        out.append("## Frame time (GPU ms, median)")
        out.append("")
        order = ["cornell", "cornell_bunny", "atrium", "sponza"]
        scenes = sorted({s for s, _ in profiles}, key=lambda s: order.index(s) if s in order else 9)
        configs = []
        for _, c in profiles:
            if c not in configs:
                configs.append(c)
        out.append("| configuration | " + " | ".join(scenes) + " |")
        out.append("|---|" + "---|" * len(scenes))
        for c in configs:
            cells = []
            for s in scenes:
                p = profiles.get((s, c))
                cells.append(fmt_ms(p.get("frame_median_ms")) if p else "—")
            out.append(f"| {c} | " + " | ".join(cells) + " |")
        out.append("")

        out.append("## Targets")
        out.append("")
        out.append(
            "The headless frame ends with two read-backs of the image to the host "
            "(`readback_hdr`, `readback_ldr`), which a viewer's frame does not have; the "
            "targets are judged on the frame without them."
        )
        out.append("")
        out.append("| target | ms | frame | without read-back | met |")
        out.append("|---|---|---|---|---|")
        for scene, config, limit, what in TARGETS:
            p = profiles.get((scene, config))
            ms = p.get("frame_median_ms") if p else None
            rb = None
            if p:
                rb = ms - sum(x["median_ms"] for x in p.get("passes", []) if x["name"].startswith("readback"))
            met = "—" if rb is None else ("yes" if rb <= limit else "no")
            out.append(f"| {what} ({scene}) | ≤ {limit:g} | {fmt_ms(ms)} | {fmt_ms(rb)} | {met} |")
        out.append("")

        out.append("## Per-pass GPU ms (median)")
        for s in scenes:
            cs = [c for c in configs if (s, c) in profiles]
            passes = []
            for c in cs:
                for p in profiles[(s, c)].get("passes", []):
                    if p["name"] not in passes:
                        passes.append(p["name"])
            out.append("")
            out.append(f"### {s}")
            out.append("")
            out.append("| pass | " + " | ".join(cs) + " |")
            out.append("|---|" + "---|" * len(cs))
            for name in passes:
                cells = []
                for c in cs:
                    v = next((p["median_ms"] for p in profiles[(s, c)].get("passes", []) if p["name"] == name), None)
                    cells.append(fmt_ms(v))
                out.append(f"| {name} | " + " | ".join(cells) + " |")
            cells = [fmt_ms(profiles[(s, c)].get("frame_median_ms")) for c in cs]
            out.append("| **frame** | " + " | ".join(cells) + " |")
            setup = []
            for c in cs:
                for p in profiles[(s, c)].get("setup", []) or []:
                    if isinstance(p, dict) and p.get("name") not in [x for x, _ in setup]:
                        setup.append((p.get("name"), p.get("total_ms")))
            if setup:
                out.append("")
                out.append("Setup (once): " + ", ".join(f"{n} {fmt_ms(v)} ms" for n, v in setup if v is not None))
        out.append("")

    ladder = []
    for name in status:
        if name.startswith("ladder_"):
            data = load_json(os.path.join(res, name + ".out"))
            if data:
                ladder.append((name[len("ladder_"):], data))
    if ladder:
        base = next((d["frame_median_ms"] for n, d in ladder if n == "direct"), None)
        out.append("## The ladder (Cornell, profile at the reference's size)")
        out.append("")
        out.append("| rung | frame ms | GI ms (frame − direct frame) |")
        out.append("|---|---|---|")
        for n, d in ladder:
            ms = d.get("frame_median_ms")
            gi = None if base is None or n == "direct" else ms - base
            out.append(f"| {n} | {fmt_ms(ms)} | {fmt_ms(gi)} |")
        out.append("")

    for name, title in [
        ("bench_traverse", "bench traverse"),
        ("bench_ssgi", "bench ssgi"),
        ("bench_voxelize_sweep", "bench voxelize-sweep"),
        ("bench_voxelize", "bench voxelize"),
        ("bench_leak", "bench leak"),
        ("bench_flicker", "bench flicker"),
    ]:
        text = read(os.path.join(res, name + ".out")).strip()
        if not text:
            continue
        out.append(f"## {title}")
        out.append("")
        data = None
        try:
            data = json.loads(text)
        except json.JSONDecodeError:
            pass
        out.append("```" + ("json" if data is not None else "text"))
        out.append(json.dumps(data, indent=1)[:6000] if data is not None else text[:6000])
        out.append("```")
        out.append("")

    sweep_csv = os.path.join(res, "sweep", "sweep.csv")
    if os.path.exists(sweep_csv):
        with open(sweep_csv, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
        out.append("## Sweep")
        out.append("")
        out.append(f"{len(rows)} rows in sweep/sweep.csv (`tools/sweep-table` prints them as tables).")
        out.append("")
    rows = []
    for real_csv in sorted(glob.glob(os.path.join(res, "sweep_real", "*", "sweep.csv"))):
        with open(real_csv, newline="", encoding="utf-8") as f:
            rows += list(csv.DictReader(f))
    if rows:
        out.append("## Sweep of the real scenes (against their authors' references)")
        out.append("")
        out.append("| scene | configuration | frame ms | image ms | relMSE | FLIP |")
        out.append("|---|---|---|---|---|---|")
        for r in rows:
            out.append(
                f"| {r['scene']} | {r['config']} | {float(r['frame_median_ms']):.3f} "
                f"| {float(r['image_ms']):.3f} | {float(r['rel_mse']):.4g} | {float(r['flip']):.3f} |"
            )
        out.append("")
    print("\n".join(out))


if __name__ == "__main__":
    main()
