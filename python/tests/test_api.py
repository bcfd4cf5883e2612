"""woven's Python API against the CLI: the same images bit for bit, the same maps and
metrics, and errors raised as exceptions with woven's message."""
import json
import math

import numpy as np
import pytest

import woven

TWILL = "examples/twill.json"


def bits(a):
    return np.ascontiguousarray(a, dtype=np.float32).view(np.uint32)


@pytest.mark.parametrize("scene", ["flat45", "cylinder"])
def test_render_equals_cli(root, cli, tmp_path, scene):
    params = root / TWILL
    cli("render", "--params", params, "--scene", scene, "--spp", 4, "--seed", 7, "--threads", 2,
        "-o", tmp_path / "r.png", "--quiet")
    cli("render", "--params", params, "--scene", scene, "--spp", 4, "--seed", 7, "--threads", 2,
        "-o", tmp_path / "r.exr", "--quiet")
    r = woven.render(params, scene, spp=4, seed=7, threads=2)
    png = woven.read_image(tmp_path / "r.png")  # 8-bit values / 255, as woven reads them
    assert r.png.shape == png.shape and r.png.dtype == np.uint8
    assert np.array_equal(bits(r.png.astype(np.float32) / np.float32(255)), bits(png))
    assert np.array_equal(bits(r.radiance), bits(woven.read_image(tmp_path / "r.exr")))
    # another thread count, a dict and a Params give the same image
    r2 = woven.render(json.loads(params.read_text()), scene, spp=4, seed=7, threads=1)
    assert np.array_equal(bits(r2.capture), bits(r.capture))
    r3 = woven.render(woven.Params(params), scene, spp=4, seed=7)
    assert np.array_equal(bits(r3.radiance), bits(r.radiance))


def test_scene_capture_is_the_camera(root):
    r = woven.render(root / TWILL, "flat45", spp=2)
    exposure = woven.scene_info("flat45")["exposure"]
    cap = woven.scene_capture("flat45", r.radiance / np.float32(exposure))
    assert np.max(np.abs(cap - r.capture)) < 1e-6


def test_params_roundtrip(root):
    p = woven.Params(root / TWILL)
    v = p.vector
    assert v.shape == (len(woven.PARAM_NAMES),) == (37,)
    assert p.with_vector(v).json == p.json
    v2 = v.copy()
    v2[woven.PARAM_NAMES.index("roughness.warp")] = 0.3
    assert woven.Params(p.with_vector(v2).data)["roughness"]["warp"] == pytest.approx(0.3)
    for name in woven.PARAM_NAMES:
        lo, hi = woven.param_range(name)
        assert lo < hi
    assert woven.Params.default("satin")["pattern"] == "satin"


def test_maps_equal_cli(root, cli, tmp_path):
    cli("maps", "--params", root / TWILL, "--size", 64, "--format", "exr", "-o", tmp_path / "m", "--quiet")
    m = woven.maps(root / TWILL, size=64)
    meta = json.loads((tmp_path / "m" / "maps.json").read_text())
    assert m["tile_mm"] == pytest.approx(tuple(meta["tile_mm"]), rel=1e-6)
    for name in woven.MAP_NAMES:
        assert np.array_equal(bits(m[name]), bits(woven.read_image(tmp_path / "m" / f"{name}.exr"))), name
    woven.write_maps(root / TWILL, tmp_path / "m2", size=16, format="png")
    assert (tmp_path / "m2" / "normal.png").exists()


def test_maps_light_through(root):
    """The transmission and open-area maps: a sheer cloth's gaps open, (1 - 0.85)^2 of it, with
    no light through the yarns there; its yarns pass light."""
    assert {"transmission", "open"} <= set(woven.MAP_NAMES)
    m = woven.maps(root / "examples/voile.json", size=128)
    gap = m["open"][..., 0] > 0.5
    assert abs(gap.mean() - (1 - 0.85) ** 2) < 0.01
    assert np.all(m["transmission"][gap] == 0)
    assert m["transmission"][~gap].min() > 0


def test_compare_equals_cli(root, cli, tmp_path):
    a = woven.render(root / TWILL, "flat45", spp=2)
    b = woven.render(root / "examples/satin.json", "flat45", spp=2)
    woven.write_image(tmp_path / "a.png", a.capture)
    woven.write_image(tmp_path / "b.png", b.capture)
    for args in ((), ("--blur", "4", "--channels", "rgb")):
        want = json.loads(cli("compare", tmp_path / "a.png", tmp_path / "b.png", "--json", *args))
        blur = float(args[1]) if args else 0.0
        got = woven.compare(a.png, tmp_path / "b.png", blur=blur, channels="rgb" if args else "luma")
        for k in ("ssim", "wsc", "wsc_whitened", "mae"):
            assert round(got[k], 6) == pytest.approx(want[k], abs=1e-6), k
    small = woven.compare(np.zeros((20, 20, 3)), np.zeros((20, 20, 3)))
    assert small["ssim"] == pytest.approx(1.0) and small["wsc"] is None


def test_environment(tmp_path):
    env = woven.environment("studio", 64)
    assert env.shape == (32, 64, 3) and np.all(np.isfinite(env)) and env.max() > 1


def test_errors(root, tmp_path):
    with pytest.raises(woven.WovenError, match="nope.json") as e:
        woven.render(tmp_path / "nope.json", "flat45")
    assert e.value.status == 3
    bad = json.loads((root / TWILL).read_text())
    bad["twist_deg"] = 61
    with pytest.raises(woven.WovenError, match="twist_deg"):
        woven.render(bad, "flat45", spp=1)
    bad["twist_deg"] = float("nan")
    with pytest.raises(woven.WovenError):
        woven.Params(bad)
    with pytest.raises(woven.WovenError, match="no-such-scene"):
        woven.render(root / TWILL, "no-such-scene.json")
    with pytest.raises(woven.WovenError):
        woven.render(root / TWILL, {"image": {"width": -3}})
    with pytest.raises(woven.WovenError, match="spp"):
        woven.render(root / TWILL, "flat45", spp=100000)
    with pytest.raises(TypeError):
        woven.render(root / TWILL, "flat45", spp=2.5)
    with pytest.raises(ValueError):
        woven.compare(np.zeros((20, 20, 3)), np.zeros((21, 20, 3)))
    with pytest.raises(ValueError):
        woven.compare(np.zeros((20, 20)), np.zeros((20, 20)))
    with pytest.raises(woven.WovenError, match="blur"):
        woven.compare(np.zeros((20, 20, 3)), np.zeros((20, 20, 3)), blur=-1)
    with pytest.raises(woven.WovenError, match="not finite"):
        v = woven.Params(root / TWILL).vector
        v[3] = math.nan
        woven.Params(root / TWILL).with_vector(v)
    with pytest.raises(ValueError):
        woven.Params(root / TWILL).with_vector(np.zeros(5))
    with pytest.raises(woven.WovenError, match="unknown capture option"):
        woven.capture(root / "examples/photo_twill_cylinder.png", "cylinder", tmp_path / "c", bogus=1)
    with pytest.raises(woven.WovenError):
        woven.capture(tmp_path / "missing.png", "cylinder", tmp_path / "c")
    with pytest.raises(woven.WovenError):
        woven.read_image(tmp_path)
    (tmp_path / "garbage.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"x" * 40)
    with pytest.raises(woven.WovenError):
        woven.read_image(tmp_path / "garbage.png")
    with pytest.raises(woven.WovenError, match="nope"):
        woven.environment("nope", 64)


def test_capture(root, tmp_path):
    """The whole capture through the library, cut short (one iteration, no searches)."""
    out = tmp_path / "cap"
    r = woven.capture(root / "examples/photo_twill_cylinder.png", "cylinder", out, pattern="twill", iters=1,
                      iter_spp=1, align_radius=0, register_radius=0, distort_degree=0, drape="none", threads=2)
    assert r["pattern"] == "twill" and r["iterations"] == 1
    assert 0 < r["ssim_fit"] <= 1 and 0 < r["ssim_network"] <= 1
    assert r["params"].json == woven.Params(out / "params.json").json
    assert r["render"].shape == (300, 800, 3)
    # the figures `woven capture --json` gives, against the photo
    assert 0 < r["ssim_rgb_fit"] <= 1 and 0 < r["ssim_rgb_blurred_photo"] <= 1
    assert r["below_blurred_copy"] == (r["ssim_rgb_fit"] < r["ssim_rgb_blurred_photo"])
    assert r["blas_core"] and r["blas_core"].replace("_", "").isalnum()
    assert 0 < r["photo_periodic_share"] < 1 and -1 <= r["wsc_fit"] <= 1
    assert (out / "network.json").exists() and (out / "report.html").exists()
    with pytest.raises(woven.WovenError):  # an earlier capture is not replaced without force
        woven.capture(root / "examples/photo_twill_cylinder.png", "cylinder", out, pattern="twill", iters=1)


def test_capture_pair(root, tmp_path):
    """A photo pair through the library: a sheer cloth rendered lit from the front and from
    behind, captured from both (cut short), its back-lit re-render and figures returned."""
    sheer = root / "examples/voile.json"
    for name, scene in (("r.png", "flat45"), ("t.png", "flat45-back")):
        woven.write_image(tmp_path / name, woven.render(sheer, scene, spp=2, threads=2).capture)
    with pytest.raises(woven.WovenError, match="need 'transmission'"):
        woven.capture(tmp_path / "r.png", "flat45", tmp_path / "x", transmission_scene="flat45-back")
    out = tmp_path / "pair"
    r = woven.capture(tmp_path / "r.png", "flat45", out, transmission=tmp_path / "t.png", pattern="plain",
                      iters=1, iter_spp=1, register_radius=0, distort_degree=0, drape="none", threads=2)
    assert 0 < r["ssim_rgb_fit_t"] <= 1 and 0 < r["ssim_rgb_blurred_photo_t"] <= 1
    assert r["below_blurred_copy_t"] == (r["ssim_rgb_fit_t"] < r["ssim_rgb_blurred_photo_t"])
    assert 0 <= r["photo_periodic_share_t"] < 1
    assert r["render_t"].shape == (512, 512, 3) and (out / "photo_t.png").exists()
    assert r["params"].json == woven.Params(out / "params.json").json
