#!/usr/bin/env python3
"""Builds the HDR-FLIP fixture with the FLIP authors' own implementation.

Run from anywhere (needs `pip install flip-evaluator numpy`; fixture made with
flip-evaluator 1.7 and numpy 2.4):

    python3 crates/metrics/tests/data/make_hdr_flip_fixture.py

Writes, beside this script:
  hdr_flip_reference.exr, hdr_flip_test.exr  64x48 linear RGB, float32, uncompressed EXR
  hdr_flip_fixture.json                      the authors' HDR-FLIP of test vs reference:
                                             mean, start/stop exposure (stops), number of
                                             exposures, and the error map averaged over
                                             8x8 blocks (8 columns x 6 rows, row 0 = top)

The images are a toy surface caustic: a dim floor (~0.02-0.05 W m^-2 sr^-1, slightly
tinted) with a bright focus (peak ~40) and a fainter ring, i.e. about 11 stops. The test
image has the focus shifted by 1.5 px, scaled by 0.8, and the floor 10% brighter.
The images are computed in float64 and stored as float32; the EXR writer is a minimal
hand-written one (no extra dependency) and is checked by reading both files back with
flip_evaluator's own loader (tinyexr).
"""

import json
import os
import struct
import sys

import numpy as np
import flip_evaluator as flip

HERE = os.path.dirname(os.path.abspath(__file__))
W, H = 64, 48
# caustics_metrics::FLIP_PIXELS_PER_DEGREE (flip-evaluator's own default is 67.02).
PPD = 67.0


def caustic(shift_x, focus_scale, floor_scale):
    y, x = np.mgrid[0:H, 0:W].astype(np.float64)
    x += 0.5
    y += 0.5
    floor = floor_scale * (0.02 + 0.03 * x / W) * np.ones_like(y)
    cx, cy = 30.0 + shift_x, 22.0
    r2 = (x - cx) ** 2 + (y - cy) ** 2
    focus = 40.0 * np.exp(-r2 / (2.0 * 1.2 ** 2))
    ring = 1.5 * np.exp(-((np.sqrt(r2) - 9.0) ** 2) / (2.0 * 1.0 ** 2))
    lum = floor + focus_scale * (focus + ring)
    tint = np.array([1.0, 0.92, 0.75])
    return (lum[..., None] * tint[None, None, :]).astype(np.float32)


def write_exr(path, img):
    """Uncompressed single-part scanline EXR, channels B, G, R as FLOAT."""
    h, w, _ = img.shape

    def attr(name, kind, data):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(data)) + data

    chlist = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in "BGR") + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = (
        struct.pack("<ii", 20000630, 2)
        + attr("channels", "chlist", chlist)
        + attr("compression", "compression", b"\0")
        + attr("dataWindow", "box2i", box)
        + attr("displayWindow", "box2i", box)
        + attr("lineOrder", "lineOrder", b"\0")
        + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
        + attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
        + attr("screenWindowWidth", "float", struct.pack("<f", 1.0))
        + b"\0"
    )
    line_bytes = w * 3 * 4
    first = len(header) + 8 * h
    offsets = b"".join(struct.pack("<Q", first + y * (8 + line_bytes)) for y in range(h))
    lines = []
    for y in range(h):
        row = img[y].astype("<f4")
        data = row[:, 2].tobytes() + row[:, 1].tobytes() + row[:, 0].tobytes()
        lines.append(struct.pack("<ii", y, len(data)) + data)
    with open(path, "wb") as f:
        f.write(header + offsets + b"".join(lines))


ACES = [0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14]


def srgb(v):
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * np.power(v, 1.0 / 2.4) - 0.055)


def eight_bit_hdr_flip(reference, test, params):
    start, stop, n = params["startExposure"], params["stopExposure"], params["numExposures"]
    out = np.zeros(reference.shape[:2])
    for i in range(n):
        e = start + i * (stop - start) / (n - 1)
        ldr = []
        for img in (reference, test):
            x = img.astype(np.float32) * np.float32(2.0**e)
            a, b, c, d, f, g = ACES
            y = np.clip((a * x * x + b * x + c) / (d * x * x + f * x + g), 0.0, 1.0)
            ldr.append((np.round(srgb(y) * 255.0) / 255.0).astype(np.float32))
        m, _, _ = flip.evaluate(ldr[0], ldr[1], "LDR", applyMagma=False, parameters={"ppd": PPD})
        out = np.maximum(out, np.asarray(m, dtype=np.float64).reshape(out.shape))
    return out


def main():
    reference = caustic(0.0, 1.0, 1.0)
    test = caustic(1.5, 0.8, 1.1)
    paths = {}
    for name, img in [("reference", reference), ("test", test)]:
        paths[name] = os.path.join(HERE, f"hdr_flip_{name}.exr")
        write_exr(paths[name], img)
        back = np.asarray(flip.load(paths[name]), dtype=np.float32)[..., :3]
        if not np.array_equal(back, img):
            sys.exit(f"EXR round trip failed for {name}")

    error_map, mean, params = flip.evaluate(
        reference, test, "HDR", applyMagma=False, parameters={"ppd": PPD}
    )
    error_map = np.asarray(error_map, dtype=np.float64).reshape(H, W)
    blocks = error_map.reshape(H // 8, 8, W // 8, 8).mean(axis=(1, 3))
    # The same bracket with every exposure rounded to 8-bit sRGB before LDR-FLIP, as
    # nv-flip's 8-bit API forces on caustics_metrics: isolates what the rounding costs.
    q_map = eight_bit_hdr_flip(reference, test, params)
    lum = 0.2126 * reference[..., 0] + 0.7152 * reference[..., 1] + 0.0722 * reference[..., 2]
    out = {
        "tool": "flip-evaluator " + getattr(flip, "__version__", "1.7"),
        "call": 'flip_evaluator.evaluate(reference, test, "HDR", applyMagma=False, parameters={"ppd": 67.0})',
        "width": W,
        "height": H,
        "pixels_per_degree": float(params.get("ppd", 67.0)),
        "tonemapper": str(params.get("tonemapper", "ACES")),
        "reference_luminance_min": float(lum.min()),
        "reference_luminance_max": float(lum.max()),
        "mean": float(mean),
        "map_mean_f64": float(error_map.mean()),
        "start_exposure": float(params["startExposure"]),
        "stop_exposure": float(params["stopExposure"]),
        "num_exposures": int(params["numExposures"]),
        "mean_8bit_exposures": float(q_map.mean()),
        "max_abs_pixel_diff_8bit_exposures": float(np.abs(q_map - error_map).max()),
        "block_size": 8,
        "block_means": [[float(v) for v in row] for row in blocks],
    }
    with open(os.path.join(HERE, "hdr_flip_fixture.json"), "w") as f:
        json.dump(out, f, indent=1)
        f.write("\n")
    print(json.dumps({k: v for k, v in out.items() if k != "block_means"}, indent=1))


if __name__ == "__main__":
    main()
