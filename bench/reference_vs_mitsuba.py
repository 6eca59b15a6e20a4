#!/usr/bin/env python3
"""Reference efficiency at equal caustic noise: our CPU reference against Mitsuba 3's
stock particle tracer (`ptracer`), side by side on this machine (issue 17, item 5).

Paths per second are not equal work: Mitsuba's ptracer emits over the whole scene, so
most of its paths are cheap direct-light paths, while every path of ours is a caustic
path. What a user needs is the time to a caustic image of a given noise, so for each
scene this measures, in one run:

- ours: `caustics reference --seconds T --batches B` (its own B-batch standard-error
  image), its wall time as printed;
- Mitsuba: the same scene converted to Mitsuba's format (sensor, lights, materials;
  spheres, quads and open cylinders as its own shapes, heightfields as meshes of our
  grid with analytic normals, OBJ meshes with our transform), rendered with `ptracer`
  (stock settings) as B independent renders (seeds 1..B, after one warm-up render that
  pays for the JIT) of as many samples per pixel as fill its time budget, per-pixel
  standard error from the B renders; the same thread count (Dr.Jit's pool, as our
  rayon pool, one thread per core).

Noise is measured on the caustic region of our reference (the harness's rule: pixels
at least 1 % of the 99th-percentile luminance), as the harness's reference reports it:
relative standard error = Σ_region Y(σ) / Σ_region Y(caustic), with Y the Rec. 709
luminance of the per-channel standard errors. For Mitsuba the numerator is the noise of
its whole image in that region (it renders direct and caustic light together, as a user
of it would) and the denominator our caustic, so both figures are the noise on the same
caustic signal. Standard errors fall as 1/√time, so each renderer's time to the target
(default 2 %) is its measured time × (measured / target)². Mitsuba's mean over the
region is also checked against our caustic + direct light (`caustics reference
--direct`) to show that the conversion is radiometrically right.

Needs Mitsuba 3 with its LLVM variant and numpy in some Python (not a dependency of the
project):

    python3 -m venv .venv-mitsuba && .venv-mitsuba/bin/pip install mitsuba==3.7.1 numpy
    .venv-mitsuba/bin/python bench/reference_vs_mitsuba.py --scale 0.25

Mitsuba's LLVM backend needs a libLLVM (Mesa's, `libLLVM-15.so.1`, is found by
DRJIT_LIBLLVM_PATH if Dr.Jit does not find one). Writes a JSON record and a Markdown
table (default `results/reference-vs-mitsuba.{json,md}`), each written to a temporary
file and renamed.
"""

import argparse
import json
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
LUMA = np.array([0.2126, 0.7152, 0.0722])
PASS_SPP = 32
DEFAULT_SCENES = ["sphere_on_plane", "ring", "water_pool", "bumpy_glass", "glass_cushion"]


def fail(msg):
    print(f"error: {msg}", file=sys.stderr)
    sys.exit(2)


def load_scene(name, scale):
    path = ROOT / "scenes" / f"{name}.json"
    if not path.is_file():
        fail(f"{path}: no such built-in scene")
    try:
        scene = json.loads(path.read_text())
    except json.JSONDecodeError as e:
        fail(f"{path}: not JSON: {e}")
    cam = scene["camera"]
    cam["width"] = max(8, round(cam["width"] * scale))
    cam["height"] = max(8, round(cam["height"] * scale))
    return path, scene


def normalize(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def quad_axes(n):
    """crates/scene/src/shape.rs quad_axes: a = +Z if |n.z| < 0.999 else +X."""
    a = np.array([0.0, 0.0, 1.0]) if abs(n[2]) < 0.999 else np.array([1.0, 0.0, 0.0])
    u = normalize(np.cross(n, a))
    return u, np.cross(n, u)


def write_ply(path, positions, normals, faces):
    """A binary little-endian PLY of positions, vertex normals and triangles."""
    vertices = np.hstack([positions, normals]).astype("<f4")
    tris = np.empty(len(faces), dtype=[("n", "u1"), ("v", "<i4", (3,))])
    tris["n"] = 3
    tris["v"] = np.asarray(faces, dtype="<i4")
    with open(path, "wb") as f:
        f.write(
            (
                "ply\nformat binary_little_endian 1.0\n"
                f"element vertex {len(vertices)}\n"
                "property float x\nproperty float y\nproperty float z\n"
                "property float nx\nproperty float ny\nproperty float nz\n"
                f"element face {len(tris)}\nproperty list uchar int vertex_indices\nend_header\n"
            ).encode()
        )
        f.write(vertices.tobytes())
        f.write(tris.tobytes())


def heightfield_ply(shape, path):
    """The grid of crates/scene Heightfield: `resolution` vertices per axis over `size`,
    y = center.y + Σ a sin(2π/λ d̂·(x, z) + phase), analytic normals, +y outside."""
    c = np.asarray(shape["center"], dtype=np.float64)
    sx, sz = shape["size"]
    nx, nz = shape["resolution"]
    xs = c[0] - 0.5 * sx + sx * np.arange(nx) / (nx - 1)
    zs = c[2] - 0.5 * sz + sz * np.arange(nz) / (nz - 1)
    x, z = np.meshgrid(xs, zs)  # rows of z, columns of x
    y = np.full_like(x, c[1])
    gx = np.zeros_like(x)
    gz = np.zeros_like(x)
    for w in shape.get("waves", []):
        d = normalize(w["direction"])
        k = 2 * math.pi / w["wavelength"]
        arg = k * (d[0] * x + d[1] * z) + w.get("phase", 0.0)
        y += w["amplitude"] * np.sin(arg)
        gx += d[0] * w["amplitude"] * k * np.cos(arg)
        gz += d[1] * w["amplitude"] * k * np.cos(arg)
    positions = np.stack([x, y, z], axis=-1).reshape(-1, 3)
    normals = np.stack([-gx, np.ones_like(x), -gz], axis=-1)
    normals /= np.linalg.norm(normals, axis=-1, keepdims=True)
    normals = normals.reshape(-1, 3)
    faces = []
    for j in range(nz - 1):
        for i in range(nx - 1):
            v00 = j * nx + i
            v10, v01, v11 = v00 + 1, v00 + nx, v00 + nx + 1
            # Counter-clockwise seen from +y: the facet normal points up (outside).
            faces.append((v00, v01, v10))
            faces.append((v10, v01, v11))
    write_ply(path, positions, normals, faces)


def mitsuba_scene(mi, scene, scene_path, workdir):
    """Our scene as a Mitsuba scene dict (the shapes, materials and lights the built-ins
    use; anything else is an error naming it)."""
    T = mi.ScalarTransform4f
    cam = scene["camera"]
    out = {
        "type": "scene",
        # Stock settings, rendered in passes of PASS_SPP samples per pixel so that a
        # render's wavefront stays a few million paths.
        "integrator": {"type": "ptracer", "samples_per_pass": PASS_SPP},
        "sensor": {
            "type": "perspective",
            "fov_axis": "y",
            "fov": cam["fov_y_deg"],
            "to_world": T().look_at(origin=cam["eye"], target=cam["target"], up=cam["up"]),
            "film": {
                "type": "hdrfilm",
                "width": cam["width"],
                "height": cam["height"],
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent", "sample_count": 1},
        },
    }
    bsdfs = {}
    for name, m in scene["materials"].items():
        kind = m["type"]
        if kind == "diffuse":
            bsdfs[name] = {"type": "diffuse", "reflectance": {"type": "rgb", "value": m["albedo"]}}
        elif kind == "dielectric":
            bsdfs[name] = {"type": "dielectric", "int_ior": m["ior"], "ext_ior": 1.0}
        elif kind == "mirror":
            # Both sides reflect, as our mirrors do (the inside of a ring).
            bsdfs[name] = {
                "type": "twosided",
                "bsdf": {
                    "type": "conductor",
                    "material": "none",
                    "specular_reflectance": {"type": "rgb", "value": m["reflectance"]},
                },
            }
        else:
            fail(f"{scene_path}: materials.{name}: type {kind!r} has no Mitsuba conversion here")
    for i, light in enumerate(scene["lights"]):
        kind = light["type"]
        if kind == "directional":
            out[f"light{i}"] = {
                "type": "directional",
                "direction": list(normalize(light["direction"])),
                "irradiance": {"type": "rgb", "value": light["irradiance"]},
            }
        elif kind == "point":
            out[f"light{i}"] = {
                "type": "point",
                "position": light["position"],
                "intensity": {"type": "rgb", "value": light["intensity"]},
            }
        else:
            fail(f"{scene_path}: lights[{i}]: type {kind!r} has no Mitsuba conversion here")
    for i, obj in enumerate(scene["objects"]):
        s = obj["shape"]
        kind = s["type"]
        bsdf = bsdfs[obj["material"]]
        if kind == "sphere":
            shape = {"type": "sphere", "center": s["center"], "radius": s["radius"]}
        elif kind == "quad":
            n = normalize(s["normal"])
            u, v = quad_axes(n)
            c = np.asarray(s["center"], dtype=np.float64)
            hu, hv = 0.5 * s["size"][0], 0.5 * s["size"][1]
            # Mitsuba's rectangle spans [-1, 1]² in xy with normal +z.
            m = np.identity(4)
            m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = u * hu, v * hv, n, c
            shape = {"type": "rectangle", "to_world": T(m.tolist())}
        elif kind == "cylinder":
            c = np.asarray(s["center"], dtype=np.float64)
            a = normalize(s["axis"]) * 0.5 * s["height"]
            shape = {"type": "cylinder", "p0": list(c - a), "p1": list(c + a), "radius": s["radius"]}
        elif kind == "heightfield":
            ply = workdir / f"heightfield{i}.ply"
            heightfield_ply(s, ply)
            shape = {"type": "ply", "filename": str(ply), "face_normals": False}
        elif kind == "mesh":
            path = (scene_path.parent / s["path"]).resolve()
            if path.suffix.lower() != ".obj":
                fail(f"{scene_path}: objects[{i}].shape.path: {path.name}: only OBJ meshes convert here")
            t = s.get("transform", {})
            rx, ry, rz = t.get("rotate_deg", [0, 0, 0])
            # T · Rz · Ry · Rx · S, as crates/scene MeshTransform.
            to_world = (
                T()
                .translate(t.get("translate", [0, 0, 0]))
                .rotate([0, 0, 1], rz)
                .rotate([0, 1, 0], ry)
                .rotate([1, 0, 0], rx)
                .scale(t.get("scale", 1.0))
            )
            shape = {"type": "obj", "filename": str(path), "to_world": to_world, "face_normals": False}
        else:
            fail(f"{scene_path}: objects[{i}].shape: type {kind!r} has no Mitsuba conversion here")
        shape["bsdf"] = bsdf
        out[f"object{i}"] = shape
    return out


def read_exr(path):
    import mitsuba as mi

    return np.array(mi.TensorXf(mi.Bitmap(str(path)))).astype(np.float64)[..., :3]


def luminance(img):
    return img @ LUMA


def caustic_region(caustic):
    """crates/metrics flux.rs caustic_region: luminance ≥ 1 % of the 99th percentile
    (nearest rank) of the positive luminances."""
    y = luminance(caustic)
    pos = np.sort(y[np.isfinite(y) & (y > 0)])
    if len(pos) == 0:
        return np.zeros_like(y, dtype=bool)
    p99 = pos[int(round((len(pos) - 1) * 0.99))]
    return y >= 0.01 * p99


def ours(binary, scene_file, seconds, batches, direct, outdir):
    cmd = [
        str(binary), "reference", "--scene", str(scene_file), "--seconds", f"{seconds:g}",
        "--batches", str(batches), "--out", str(outdir),
    ]
    if direct:
        cmd.append("--direct")
    run = subprocess.run(cmd, capture_output=True, text=True)
    if run.returncode != 0:
        fail(f"{' '.join(cmd)} failed:\n{run.stderr}")
    m = re.search(r"(\d+) photons in ([0-9.]+) s", run.stdout + run.stderr)
    if not m:
        fail(f"{' '.join(cmd)}: no 'N photons in T s' line in its output:\n{run.stdout}{run.stderr}")
    return int(m.group(1)), float(m.group(2))


def mitsuba_batches(mi, scene_dict, budget_s, k):
    """K independent ptracer renders (seeds 1..K) of as many samples per pixel as fill
    `budget_s` seconds in all (from a timed render after a warm-up render that
    pays for the JIT); their images, the wall seconds of the K and the spp."""
    scene = mi.load_dict(scene_dict)
    np.array(mi.render(scene, spp=1, seed=0))  # compile the kernels once
    # Seconds per spp from a render long enough that a render's fixed cost is small:
    # a first guess at one pass, then one render of about a tenth of a render's share.
    whole = lambda n: max(PASS_SPP, PASS_SPP * round(n / PASS_SPP))  # whole passes
    spp, per_spp = PASS_SPP, None
    for _ in range(2):
        t0 = time.perf_counter()
        np.array(mi.render(scene, spp=spp, seed=k + 1))
        per_spp = (time.perf_counter() - t0) / spp
        spp = whole(0.1 * budget_s / (k * per_spp))
    spp = whole(budget_s / (k * per_spp))
    images, seconds = [], 0.0
    for seed in range(1, k + 1):
        t0 = time.perf_counter()
        img = mi.render(scene, spp=spp, seed=seed)
        arr = np.array(img, dtype=np.float64)[..., :3]  # forces evaluation
        seconds += time.perf_counter() - t0
        images.append(arr)
    return np.stack(images), seconds, spp


def atomic_write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", nargs="+", default=DEFAULT_SCENES)
    ap.add_argument("--scale", type=float, default=0.25, help="camera resolution scale (default 0.25: 256x192)")
    ap.add_argument("--target", type=float, default=0.02, help="relative standard error to reach (default 2 %%)")
    ap.add_argument("--ours-seconds", type=float, default=20.0, help="our reference's time per scene (caustics reference --time)")
    ap.add_argument("--batches", type=int, default=16, help="our reference's batches, and Mitsuba's renders, for the standard errors (the same count, so the estimators' small-sample bias is the same)")
    ap.add_argument("--mitsuba-seconds", type=float, default=60.0, help="Mitsuba's time per scene over all its renders")
    ap.add_argument("--caustics", default=str(ROOT / "target" / "release" / "caustics"), help="the caustics binary")
    ap.add_argument("--out", default=str(ROOT / "results" / "reference-vs-mitsuba"), help="output path without extension")
    args = ap.parse_args()
    if not (0 < args.target < 1):
        fail(f"--target: expected a relative standard error in (0, 1), got {args.target}")
    if args.scale <= 0 or args.batches < 2 or args.ours_seconds <= 0 or args.mitsuba_seconds <= 0:
        fail("--scale > 0, --batches >= 2, --ours-seconds > 0 and --mitsuba-seconds > 0 are expected")
    binary = Path(args.caustics)
    if not binary.is_file():
        fail(f"--caustics: {binary}: no such file (cargo build --release -p caustics)")
    try:
        import mitsuba as mi
        import drjit as dr
    except ImportError as e:
        fail(f"{e}: install Mitsuba 3 (see this file's docstring)")
    mi.set_variant("llvm_ad_rgb")
    threads = os.cpu_count()
    dr.set_thread_count(threads)

    rows = []
    for name in args.scenes:
        scene_path, scene = load_scene(name, args.scale)
        with tempfile.TemporaryDirectory() as tmp:
            tmp = Path(tmp)
            # The scaled scene in the temporary folder, its mesh paths made absolute.
            for obj in scene["objects"]:
                if obj["shape"]["type"] == "mesh":
                    obj["shape"]["path"] = str((scene_path.parent / obj["shape"]["path"]).resolve())
            scaled = tmp / f"{name}.json"
            scaled.write_text(json.dumps(scene))
            photons, ours_s = ours(binary, scaled, args.ours_seconds, args.batches, True, tmp / "ours")
            caustic = read_exr(tmp / "ours" / "caustic.exr")
            stderr = read_exr(tmp / "ours" / "stderr.exr")
            direct = read_exr(tmp / "ours" / "direct.exr")
            region = caustic_region(caustic)
            signal = luminance(caustic)[region].sum()
            ours_rel = luminance(stderr)[region].sum() / signal
            md = mitsuba_scene(mi, scene, scaled, tmp)
            images, mi_s, spp = mitsuba_batches(mi, md, args.mitsuba_seconds, args.batches)
        mean = images.mean(axis=0)
        se = images.std(axis=0, ddof=1) / math.sqrt(args.batches)
        mi_rel = luminance(se)[region].sum() / signal
        mi_paths = spp * args.batches * scene["camera"]["width"] * scene["camera"]["height"]
        ours_t = ours_s * (ours_rel / args.target) ** 2
        mi_t = mi_s * (mi_rel / args.target) ** 2
        # Mitsuba renders direct + caustic light: its mean over the region against ours.
        agreement = luminance(mean)[region].sum() / (signal + luminance(direct)[region].sum())
        row = {
            "scene": name,
            "width": scene["camera"]["width"],
            "height": scene["camera"]["height"],
            "region_pixels": int(region.sum()),
            "ours_photons": photons,
            "ours_seconds": ours_s,
            "ours_paths_per_s": photons / ours_s,
            "ours_rel_stderr": ours_rel,
            "ours_seconds_to_target": ours_t,
            "mitsuba_spp_per_render": spp,
            "mitsuba_paths": mi_paths,
            "mitsuba_seconds": mi_s,
            "mitsuba_paths_per_s": mi_paths / mi_s,
            "mitsuba_rel_stderr": mi_rel,
            "mitsuba_seconds_to_target": mi_t,
            "speedup_at_equal_noise": mi_t / ours_t,
            "mitsuba_over_ours_mean_in_region": agreement,
        }
        print(json.dumps(row), flush=True)
        rows.append(row)

    def git(*a):
        return subprocess.run(["git", *a], cwd=ROOT, capture_output=True, text=True).stdout.strip()

    record = {
        "commit": git("rev-parse", "HEAD"),
        "dirty": bool(git("status", "--porcelain", "--untracked-files=no")),
        "what": "time to a caustic image of equal relative standard error over the caustic region: our reference (caustics reference) and Mitsuba 3's ptracer, side by side",
        "target_rel_stderr": args.target,
        "machine": {"cpu_threads": threads, "mitsuba": mi.__version__, "drjit": dr.__version__, "variant": mi.variant()},
        "settings": {"scale": args.scale, "ours_seconds": args.ours_seconds, "mitsuba_seconds": args.mitsuba_seconds, "batches": args.batches},
        "scenes": rows,
    }
    out = Path(args.out)
    atomic_write(out.with_suffix(".json"), json.dumps(record, indent=2) + "\n")
    lines = [
        f"# Reference against Mitsuba 3 ptracer at equal caustic noise ({100 * args.target:g} % relative standard error)",
        "",
        f"`bench/reference_vs_mitsuba.py --scale {args.scale:g}` on {threads} threads; Mitsuba {mi.__version__} `{mi.variant()}`, "
        f"{args.batches} renders per scene (spp set to fill about {args.mitsuba_seconds:g} s); ours {args.batches} batches in {args.ours_seconds:g} s per scene. "
        "Noise = Σ Y(σ) / Σ Y(our caustic) over our reference's caustic region; time to the target = time × (noise / target)². "
        "Mitsuba's noise is its whole image's (direct and caustic light) on our caustic's signal; "
        "`mean ratio` = Mitsuba's mean over the region ÷ our caustic + direct (1 = the conversion is radiometrically right).",
        "",
        "| scene | size | region px | ours: s | ours: paths/s | ours: noise | ours: s to target | Mitsuba: s | Mitsuba: paths/s | Mitsuba: noise | Mitsuba: s to target | speed-up | mean ratio |",
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['scene']} | {r['width']}×{r['height']} | {r['region_pixels']} | {r['ours_seconds']:.1f} | {r['ours_paths_per_s'] / 1e6:.2f} M | "
            f"{100 * r['ours_rel_stderr']:.2f} % | {r['ours_seconds_to_target']:.1f} | {r['mitsuba_seconds']:.1f} | {r['mitsuba_paths_per_s'] / 1e6:.2f} M | "
            f"{100 * r['mitsuba_rel_stderr']:.2f} % | {r['mitsuba_seconds_to_target']:.1f} | "
            f"{r['speedup_at_equal_noise']:.1f}× | {r['mitsuba_over_ours_mean_in_region']:.3f} |"
        )
    atomic_write(out.with_suffix(".md"), "\n".join(lines) + "\n")
    print(f"written {out.with_suffix('.json')} and {out.with_suffix('.md')}")


if __name__ == "__main__":
    main()
