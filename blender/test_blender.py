"""Blender against woven (ctest: blender): the woven_import add-on's material rendered by
Blender's Cycles (CPU, headless) in the flat45 capture rig, in the same rig lit from behind
(flat45-back: the light through the cloth) and on the draped cloth of
scenes/drape-studio.json, compared with woven's own render of the same camera and light:
SSIM of 4-px Gaussian blurs, per RGB channel (woven compare --blur 4 --channels rgb), and
on the back-lit curtain of scenes/curtain-window.json. Both flat swatches and the curtain
must reach 0.95; the drape's number is printed.

    PYTHONPATH=python /usr/bin/python3 blender/test_blender.py build/woven [OUTDIR]
Exit 77 (skipped) when Blender is not installed."""
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MIN_SSIM = 0.95


def srgb_response(rad):
    """A mesh scene's response of exposure 1: clip at 1, sRGB."""
    c = np.clip(rad, 0, 1)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055).astype(np.float32)


def main():
    blender = shutil.which("blender")
    if not blender:
        print("SKIPPED: Blender is not installed (scripts/install-deps.sh installs Debian's blender)")
        return 77
    import woven

    exe = Path(sys.argv[1]).resolve()
    out = Path(sys.argv[2]) if len(sys.argv) > 2 else Path(tempfile.mkdtemp(prefix="woven-blender-"))
    out.mkdir(parents=True, exist_ok=True)
    params = ROOT / "examples/twill.json"

    def run(*cmd):
        subprocess.run([str(c) for c in cmd], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)

    def blender_render(scene, exr, w, h, samples, *extra):
        r = subprocess.run([str(x) for x in (blender, "-b", "--factory-startup", "--python", ROOT / "blender/render_rig.py", "--",
                            "--scene", scene, "--out", exr, "--width", w, "--height", h, "--samples", samples,
                            *extra)], capture_output=True, text=True, env={**os.environ,
                                                                         "WOVEN_BINARY": str(exe)})
        if r.returncode or not Path(exr).exists():
            sys.stderr.write(r.stdout[-4000:] + r.stderr[-4000:])
            raise SystemExit(f"Blender failed on {scene}")

    def compare(a, b):
        j = subprocess.run([str(exe), "compare", str(a), str(b), "--blur", "4", "--channels", "rgb", "--json"],
                           check=True, capture_output=True, text=True).stdout
        return json.loads(j)

    results = {}
    # the flat45 rig at 256 x 256 (the falloff mask's sigma scaled with the image)
    s = json.loads((ROOT / "scenes/flat45.json").read_text())
    size = 256
    s["falloff"]["sigma_px"] *= size / s["image"]["width"]
    s["image"].update(width=size, height=size, spp=64)
    flat = out / "flat45.json"
    flat.write_text(json.dumps(s))
    run(exe, "render", "--params", params, "--scene", flat, "-o", out / "flat_woven.png", "--threads", 2, "--quiet")
    blender_render(flat, out / "flat_blender.exr", size, size, 32, "--params", params)
    rad = woven.read_image(out / "flat_blender.exr")
    woven.write_image(out / "flat_blender.png", woven.scene_capture(flat, rad))
    results["flat45"] = compare(out / "flat_woven.png", out / "flat_blender.png")

    # the same rig lit from behind, a sheer cloth with open gaps: the light through the yarns
    # and the gaps. Without the gap glow, which is the camera's (out of focus), not the cloth's.
    b = json.loads((ROOT / "scenes/flat45-back.json").read_text())
    b["falloff"]["sigma_px"] *= size / b["image"]["width"]
    b["image"].update(width=size, height=size, spp=64)
    b["response"].pop("gap_glow", None)
    back = out / "flat45-back.json"
    back.write_text(json.dumps(b))
    sheer = ROOT / "examples/voile.json"
    run(exe, "render", "--params", sheer, "--scene", back, "-o", out / "back_woven.png", "--threads", 2, "--quiet")
    blender_render(back, out / "back_blender.exr", size, size, 32, "--params", sheer)
    rad = woven.read_image(out / "back_blender.exr")
    woven.write_image(out / "back_blender.png", woven.scene_capture(back, rad))
    results["flat45-back"] = compare(out / "back_woven.png", out / "back_blender.png")

    # the draped cloth under the studio environment, 256 x 192
    drape = ROOT / "scenes/drape-studio.json"
    d = json.loads(drape.read_text())
    env = out / "studio.exr"
    woven.write_image(env, woven.environment(d["environment"]["builtin"], d["environment"].get("width", 512)))
    run(exe, "scene", drape, "-o", out / "drape_woven.png", "--size", "256x192", "--spp", 64, "--threads", 2,
        "--quiet")
    blender_render(drape, out / "drape_blender.exr", 256, 192, 64, "--env", env)
    rad = woven.read_image(out / "drape_blender.exr") * np.float32(d.get("response", {}).get("exposure", 1))
    woven.write_image(out / "drape_blender.png", srgb_response(rad))
    results["drape"] = compare(out / "drape_woven.png", out / "drape_blender.png")

    # the back-lit curtain: a sheer cloth before a window's area light, lit by the light
    # through it, 320 x 240
    curtain = ROOT / "scenes/curtain-window.json"
    run(exe, "scene", curtain, "-o", out / "curtain_woven.png", "--size", "320x240", "--spp", 64, "--threads", 2,
        "--quiet")
    blender_render(curtain, out / "curtain_blender.exr", 320, 240, 64)
    woven.write_image(out / "curtain_blender.png", srgb_response(woven.read_image(out / "curtain_blender.exr")))
    results["curtain"] = compare(out / "curtain_woven.png", out / "curtain_blender.png")

    for k, r in results.items():
        print(f"{k}: SSIM (rgb, 4 px blur) {r['ssim']:.4f}  MAE {r['mae']:.4f}")
    print(json.dumps({k: {"ssim": r["ssim"], "mae": r["mae"]} for k, r in results.items()}))
    print(f"images in {out}")
    failed = [k for k in ("flat45", "flat45-back", "curtain") if results[k]["ssim"] < MIN_SSIM]
    for k in failed:
        print(f"FAILED: {k} SSIM {results[k]['ssim']:.4f} < {MIN_SSIM}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
