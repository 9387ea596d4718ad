"""Mitsuba 3 references of the third-party scenes, rendered from their AUTHORS' scene files.

Run through `tools/reference-authors`, which provides the virtual environment. Unlike
`tools/reference`, which renders voxgi's own export of a scene, this renders the scene as its
authors described it (assets/realscenes/*/), so that the reference shares none of voxgi's
material mapping. What has to change for Mitsuba 3 is changed here, and said here:

- Modern Hall (`modern_hall/scene.xml`, Mitsuba 0.5): Mitsuba 3 upgrades the file itself
  (camelCase names); the film properties it rejects (`banner`, `high_quality_edges`) are dropped.
- Sponza (`sponza/mitsuba/scene.xml`, Mitsuba 0.6): its meshes are in a `sponza.serialized` file
  that was not published with it; `sponza.obj` holds the same 37 shapes as groups named after
  the shape ids, already in world space, so each shape becomes an OBJ of its group without the
  `toWorld` matrix. Its integrator (`sppm`, absent from Mitsuba 3) becomes `path` with the same
  `maxDepth` (6), and its one `phong` BSDF (absent from Mitsuba 3: diffuse 0.94/0.87/0.74,
  specular 0.034, exponent 1.07, a lobe nearly as wide as a cosine) becomes `diffuse` with the
  sum of both albedos.
- CornellBox-Original has no scene file: the OBJ is the scene. The XML written here splits it
  by material (Mitsuba's OBJ loader ignores the MTL), gives every material a `diffuse` BSDF
  with its `Kd` (all have Ks 0) and the `light` material an `area` emitter with its `Ke`
  (17, 12, 4), and states the camera (the one of `assets/scenes/cornell_original.toml`).

The film is set to --width x --height (the aspect of the authors' 1280x720 is kept by the
default 320x180), the sampler to --spp; the box filter matches voxgi's one sample per pixel
centre better than the authors' tent filter at this size, so the filter is set to `box`.
"""

import argparse
import os
import subprocess
import sys
import xml.etree.ElementTree as ET

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REAL = os.path.join(ROOT, "assets", "realscenes")

# The camera of the Cornell box, shared with assets/scenes/cornell_original.toml: on the box's
# axis 2.41 m in front of its open side, a 40-degree vertical field that shows the whole back
# wall and cuts the front edges a little.
CORNELL_CAMERA = {"origin": "0, 1, 3.4", "target": "0, 1, 0", "up": "0, 1, 0", "fov_y": 40.0}


def parse_args(argv):
    p = argparse.ArgumentParser(prog="tools/reference-authors", description=__doc__.split("\n")[0])
    p.add_argument("scene", choices=["modern_hall", "sponza", "cornell_original"])
    p.add_argument("out", help="output .exr path")
    p.add_argument("--spp", type=int, default=256, help="samples per pixel (default 256)")
    p.add_argument("--width", type=int, default=None, help="film width (default 320; 256 for the Cornell box)")
    p.add_argument("--height", type=int, default=None, help="film height (default 180; 256 for the Cornell box)")
    p.add_argument("--max-depth", type=int, default=None,
                   help="path segments (default: the authors' maxDepth; 64 for the Cornell box)")
    p.add_argument("--work", default=os.path.join(ROOT, "out", "authors"),
                   help="where the rewritten XML and split meshes go (default out/authors)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--preview", default=None, metavar="PNG")
    return p.parse_args(argv)


def read_obj(path):
    """Positions, texture coordinates, normals and faces of an OBJ file, faces as lists of
    (v, vt, vn) absolute 1-based indices (0 where absent), each with its group and material."""
    v, vt, vn, faces = [], [], [], []
    group, mtl = "default", None
    with open(path) as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            kw = parts[0]
            if kw == "v":
                v.append(parts[1:4])
            elif kw == "vt":
                vt.append(parts[1:3])
            elif kw == "vn":
                vn.append(parts[1:4])
            elif kw == "g":
                group = parts[1] if len(parts) > 1 else "default"
            elif kw == "usemtl":
                mtl = parts[1]
            elif kw == "f":
                corners = []
                for c in parts[1:]:
                    idx = (c.split("/") + ["", ""])[:3]
                    out = []
                    for i, count in zip(idx, (len(v), len(vt), len(vn))):
                        if not i:
                            out.append(0)
                            continue
                        k = int(i)
                        # Negative indices count back from the last element read so far.
                        out.append(k if k > 0 else count + 1 + k)
                    corners.append(tuple(out))
                faces.append((group, mtl, corners))
    return v, vt, vn, faces


def write_split(obj, key, outdir):
    """Writes one OBJ per group (key 0) or material (key 1) of `obj`, triangulated as fans and
    reindexed; returns {name: path}."""
    v, vt, vn, faces = read_obj(obj)
    parts = {}
    for face in faces:
        parts.setdefault(face[key], []).append(face[2])
    os.makedirs(outdir, exist_ok=True)
    paths = {}
    for name, polys in parts.items():
        remap = [{}, {}, {}]
        lines_v, lines_vt, lines_vn, lines_f = [], [], [], []
        sources = (v, vt, vn)
        sinks = (lines_v, lines_vt, lines_vn)
        prefixes = ("v", "vt", "vn")

        def local(kind, i):
            if i == 0:
                return ""
            if i not in remap[kind]:
                remap[kind][i] = len(remap[kind]) + 1
                sinks[kind].append(prefixes[kind] + " " + " ".join(sources[kind][i - 1]))
            return str(remap[kind][i])

        def corner(c):
            a, b, n = (local(k, c[k]) for k in range(3))
            if n:
                return f"{a}/{b}/{n}"
            return f"{a}/{b}" if b else a

        for poly in polys:
            for j in range(1, len(poly) - 1):
                lines_f.append("f " + " ".join(corner(c) for c in (poly[0], poly[j], poly[j + 1])))
        path = os.path.join(outdir, f"{name}.obj")
        with open(path, "w") as f:
            f.write("\n".join(lines_v + lines_vt + lines_vn + lines_f) + "\n")
        paths[name] = path
    return paths


def absolutize(root, base):
    """Makes every `filename` string absolute, so the rewritten XML may live anywhere."""
    for s in root.iter("string"):
        if s.get("name") == "filename" and not os.path.isabs(s.get("value")):
            s.set("value", os.path.normpath(os.path.join(base, s.get("value"))))


def set_film(root, width, height, spp):
    sensor = root.find("sensor")
    film = sensor.find("film")
    for child in list(film):
        name = child.get("name")
        # Mitsuba 3 rejects these 0.5/0.6 film properties.
        if name in ("banner", "high_quality_edges", "highQualityEdges") or child.tag == "rfilter":
            film.remove(child)
    for child in list(film):
        if child.get("name") in ("width", "height"):
            film.remove(child)
    ET.SubElement(film, "integer", name="width", value=str(width))
    ET.SubElement(film, "integer", name="height", value=str(height))
    ET.SubElement(film, "rfilter", type="box")
    sampler = sensor.find("sampler")
    for child in list(sampler):
        sampler.remove(child)
    ET.SubElement(sampler, "integer", name="sampleCount", value=str(spp))


def modern_hall(args, work):
    base = os.path.join(REAL, "modern_hall")
    tree = ET.parse(os.path.join(base, "scene.xml"))
    root = tree.getroot()
    absolutize(root, base)
    set_film(root, args.width or 320, args.height or 180, args.spp)
    if args.max_depth is not None:
        root.find("integrator").find("integer").set("value", str(args.max_depth))
    return tree


def sponza(args, work):
    base = os.path.join(REAL, "sponza", "mitsuba")
    tree = ET.parse(os.path.join(base, "scene.xml"))
    root = tree.getroot()
    absolutize(root, os.path.join(REAL, "sponza"))
    set_film(root, args.width or 320, args.height or 180, args.spp)
    for d in root.findall("default"):
        root.remove(d)
    old = root.find("integrator")
    depth = old.find("integer[@name='maxDepth']").get("value")
    old.clear()
    old.set("type", "path")
    ET.SubElement(old, "integer", name="maxDepth",
                  value=str(args.max_depth) if args.max_depth is not None else depth)
    for b in root.findall("bsdf"):
        if b.get("type") == "phong":
            kd = [float(x) for x in b.find("rgb[@name='diffuseReflectance']").get("value").split()]
            ks = [float(x) for x in b.find("rgb[@name='specularReflectance']").get("value").split()]
            bsdf_id = b.get("id")
            b.clear()
            b.set("type", "diffuse")
            b.set("id", bsdf_id)
            ET.SubElement(b, "rgb", name="reflectance",
                          value=" ".join(f"{d + s:.6f}" for d, s in zip(kd, ks)))
    meshes = write_split(os.path.join(REAL, "sponza", "sponza.obj"), 0, os.path.join(work, "meshes"))
    for shape in root.findall("shape"):
        if shape.get("type") != "serialized":
            continue
        sid = shape.get("id")
        if sid not in meshes:
            sys.exit(f"tools/reference-authors: sponza.obj has no group {sid}")
        bsdf = shape.find("ref")
        shape.clear()
        shape.set("type", "obj")
        shape.set("id", sid)
        ET.SubElement(shape, "string", name="filename", value=meshes[sid])
        shape.append(bsdf)
    return tree


def cornell_original(args, work):
    base = os.path.join(REAL, "cornell_original")
    obj = os.path.join(base, "CornellBox-Original.obj")
    kd, ke, mtl = {}, {}, None
    with open(os.path.join(base, "CornellBox-Original.mtl")) as f:
        for line in f:
            parts = line.split("#")[0].split()
            if not parts:
                continue
            if parts[0] == "newmtl":
                mtl = parts[1]
            elif parts[0] == "Kd":
                kd[mtl] = parts[1:4]
            elif parts[0] == "Ke":
                ke[mtl] = parts[1:4]
    meshes = write_split(obj, 1, os.path.join(work, "meshes"))
    width, height = args.width or 256, args.height or 256
    c = CORNELL_CAMERA
    lines = [
        '<scene version="3.0.0">',
        f'  <integrator type="path"><integer name="max_depth" '
        f'value="{args.max_depth if args.max_depth is not None else 64}"/></integrator>',
        '  <sensor type="perspective">',
        f'    <float name="fov" value="{c["fov_y"]}"/><string name="fov_axis" value="y"/>',
        '    <float name="near_clip" value="0.01"/><float name="far_clip" value="100"/>',
        f'    <transform name="to_world"><lookat origin="{c["origin"]}" target="{c["target"]}" '
        f'up="{c["up"]}"/></transform>',
        f'    <sampler type="independent"><integer name="sample_count" value="{args.spp}"/></sampler>',
        f'    <film type="hdrfilm"><integer name="width" value="{width}"/>'
        f'<integer name="height" value="{height}"/><rfilter type="box"/></film>',
        '  </sensor>',
    ]
    for name, path in meshes.items():
        lines.append(f'  <shape type="obj" id="{name}"><string name="filename" value="{path}"/>')
        lines.append(f'    <bsdf type="diffuse"><rgb name="reflectance" value="{" ".join(kd[name])}"/></bsdf>')
        if name in ke and any(float(x) > 0 for x in ke[name]):
            lines.append(f'    <emitter type="area"><rgb name="radiance" value="{" ".join(ke[name])}"/></emitter>')
        lines.append("  </shape>")
    lines.append("</scene>")
    return ET.ElementTree(ET.fromstring("\n".join(lines)))


def main(argv):
    args = parse_args(argv)
    work = os.path.join(os.path.abspath(args.work), args.scene)
    os.makedirs(work, exist_ok=True)
    tree = {"modern_hall": modern_hall, "sponza": sponza, "cornell_original": cornell_original}[
        args.scene](args, work)
    # tools/reference.py passes the seed as a parameter of the file, as voxgi's export has it.
    root = tree.getroot()
    root.insert(0, ET.Element("default", name="seed", value="0"))
    ET.SubElement(root.find("sensor").find("sampler"), "integer", name="seed", value="$seed")
    xml = os.path.join(work, "scene.xml")
    tree.write(xml)
    print(f"tools/reference-authors: wrote {xml}", flush=True)
    cmd = [sys.executable, os.path.join(ROOT, "tools", "reference.py"), xml, args.out,
           "--seed", str(args.seed)]
    if args.preview:
        cmd += ["--preview", args.preview]
    sys.exit(subprocess.call(cmd))


if __name__ == "__main__":
    main(sys.argv[1:])
