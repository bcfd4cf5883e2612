"""woven.torch: the differentiable render against the plain render and against finite
differences, and its errors. Skipped (with the reason) when PyTorch is not installed."""
import math

import numpy as np
import pytest

import woven

torch = pytest.importorskip("torch", reason="python3-torch is not installed: woven.torch is not tested")
import woven.torch as wt  # noqa: E402

TWILL = "examples/twill.json"
# A 10 x 8 window at the flat rig's centre, 4 samples a pixel: a small Jacobian for gradcheck.
WINDOW = (251, 252, 10, 8)
# The parameters checked: a diffuse and a specular albedo, both roughnesses, u_max, the
# blend and the twist (the non-linear ones through the bent-cylinder frame and SGGX).
CHECKED = ["diffuse.warp[1]", "specular.weft[2]", "roughness.warp", "roughness.weft", "inclination_deg",
           "diffuse_blend", "twist_deg", "heightfield.warp"]


@pytest.fixture(scope="module")
def base(root):
    return woven.Params(root / TWILL)


def test_forward_equals_render(base):
    r = woven.render(base, "flat45", spp=4, seed=3, threads=2)
    theta = torch.tensor(base.vector, requires_grad=True)
    img = wt.render(theta, base, "flat45", spp=4, seed=3, threads=2)
    assert img.shape == (512, 512, 3) and img.dtype == torch.float64
    assert np.array_equal(img.detach().numpy().astype(np.float32), r.capture)
    # without a gradient wanted, the plain render: the same image
    with torch.no_grad():
        img2 = wt.render(theta.float(), base, "flat45", spp=4, seed=3, threads=2)
    assert img2.dtype == torch.float32 and np.array_equal(img2.numpy(), r.capture)


def test_backward_is_the_library_gradient(base):
    """dL/dtheta of a loss through torch equals the library's vector-Jacobian product, and
    is linear in the adjoint."""
    theta = torch.tensor(base.vector, requires_grad=True)
    img = wt.render(theta, base, "flat45", spp=2, threads=2, window=(100, 100, 64, 48))
    target = torch.full_like(img, 0.3)
    loss = ((img - target) ** 2).mean()
    loss.backward()
    dcap = (2 * (img.detach() - target) / img.numel()).numpy()
    _, rec = wt.render_record(base.vector, base, "flat45", spp=2, threads=2, window=(100, 100, 64, 48))
    g, _ = rec.vjp(dcap)
    assert np.allclose(theta.grad.numpy(), g, rtol=1e-12, atol=0)
    g2, _ = rec.vjp(2 * dcap)
    assert np.allclose(g2, 2 * g, rtol=1e-6, atol=1e-12)
    assert np.any(np.abs(g) > 0)


def test_gradcheck(base):
    """torch.autograd.gradcheck of the window's capture against central differences.

    The parameters are checked in units of their range (u = (theta - lo) / (hi - lo)), so
    the angles' per-degree derivatives are not lost under the tolerance: every checked
    column of the Jacobian then reaches 0.1 or more. The render runs in double precision
    (shading and derivatives in double), but the image it returns is rounded to float: a
    value in [0, 1] carries up to 2^-25 = 3e-8 of rounding, so a central difference with
    step eps = 1e-3 is off by up to 3e-8 / eps = 3e-5 (2.2e-5 measured); the truncation
    error at that step is far below. Hence atol 1e-4 and rtol 1e-3: a wrong derivative
    (sign, factor, missing chain-rule term) misses by orders of magnitude more."""
    idx = [woven.PARAM_NAMES.index(n) for n in CHECKED]
    lo = torch.tensor([woven.param_range(i)[0] for i in idx], dtype=torch.float64)
    span = torch.tensor([woven.param_range(i)[1] for i in idx], dtype=torch.float64) - lo
    full = torch.tensor(base.vector)

    def f(u):
        theta = full.index_put((torch.tensor(idx),), lo + u * span)
        return wt.render(theta, base, "flat45", spp=4, threads=2, window=WINDOW, precision="double")

    u = ((full[idx] - lo) / span).requires_grad_(True)
    assert torch.autograd.gradcheck(f, (u,), eps=1e-3, atol=1e-4, rtol=1e-3)


def test_linear_loss_in_double(base):
    """The dot L = sum(w * capture), accumulated in double from the unrounded double
    capture, against central differences of L itself: no float rounding on either side,
    so the analytic gradient must agree to 1e-5 (the step's truncation error)."""
    rng = np.random.default_rng(1)
    w = rng.uniform(-1, 1, (WINDOW[3], WINDOW[2], 3)).astype(np.float32)
    theta = base.vector

    def dot(t):
        _, rec = wt.render_record(t, base, "flat45", spp=4, threads=2, window=WINDOW, precision="double")
        return rec.vjp(w)

    g, _ = dot(theta)
    for name in CHECKED:
        i = woven.PARAM_NAMES.index(name)
        lo, hi = woven.param_range(i)
        h = 1e-5 * (hi - lo)
        tp, tm = theta.copy(), theta.copy()
        tp[i] += h
        tm[i] -= h
        num = (dot(tp)[1] - dot(tm)[1]) / (2 * h)
        assert g[i] == pytest.approx(num, rel=1e-5, abs=1e-9), name


def test_fit_one_parameter(base):
    """A few Adam steps on the roughness move it toward the target's."""
    i = woven.PARAM_NAMES.index("roughness.warp")
    truth = base.vector
    truth[i] = 0.4
    target = wt.render(torch.tensor(truth), base, "flat45", spp=2, threads=2, window=(192, 192, 128, 128))
    theta = torch.tensor(base.vector, requires_grad=True)
    mask = torch.zeros(len(woven.PARAM_NAMES), dtype=torch.float64)
    mask[i] = 1
    opt = torch.optim.Adam([theta], lr=0.05)
    first = None
    for _ in range(8):
        opt.zero_grad()
        img = wt.render(theta, base, "flat45", spp=2, threads=2, window=(192, 192, 128, 128))
        loss = ((img - target) ** 2).mean()
        loss.backward()
        theta.grad *= mask
        opt.step()
        first = first if first is not None else loss.item()
    assert loss.item() < 0.5 * first
    assert abs(theta[i].item() - 0.4) < abs(0.75 - 0.4)


def test_errors(base):
    theta = torch.tensor(base.vector, requires_grad=True)
    with pytest.raises(ValueError, match="37"):
        wt.render(theta[:5], base, "flat45", spp=1)
    with pytest.raises(TypeError):
        wt.render(base.vector, base, "flat45", spp=1)
    with pytest.raises(TypeError):
        wt.render(torch.zeros(37, dtype=torch.int64), base, "flat45", spp=1)
    bad = theta.detach().clone()
    bad[0] = math.nan
    with pytest.raises(woven.WovenError, match="heightfield.warp"):
        wt.render(bad, base, "flat45", spp=1)
    bad[0] = 99
    with pytest.raises(woven.WovenError, match="outside"):
        wt.render(bad, base, "flat45", spp=1)
    with pytest.raises(woven.WovenError, match="window"):
        wt.render(theta, base, "flat45", spp=1, window=(500, 500, 64, 64))
    with pytest.raises(woven.WovenError):
        wt.render(theta, "/no/such/params.json", "flat45", spp=1)
    img = wt.render(theta, base, "flat45", spp=1, window=(0, 0, 16, 16))
    with pytest.raises(woven.WovenError, match="not finite"):
        (img * float("nan")).sum().backward()
    with pytest.raises(ValueError, match="precision"):
        wt.render(theta, base, "flat45", precision="half")
