"""woven.torch: woven's render as a PyTorch operation, differentiable with woven's exact
analytic gradient (include/woven/grad.h), not autograd through a re-implementation.

The parameter vector theta is a 1-D tensor of the 37 continuous parameters in the order
of woven.PARAM_NAMES (the library's wv_param_id), in the parameter file's units:

    0 heightfield.warp (beta)     1 heightfield.weft
    2-4 diffuse.warp[0..2] (k_d)  5-7 diffuse.weft[0..2]
    8-10 specular.warp[0..2] (k_s) 11-13 specular.weft[0..2]
    14 roughness.warp (alpha)     15 roughness.weft
    16 inclination_deg (u_max, degrees)  17 diffuse_blend (w)  18 twist_deg (psi, degrees)
    19-21 transmission.warp[0..2] (k_t)  22-24 transmission.weft[0..2] (light through the cloth)
    25-27 transmission_specular.warp[0..2] (k_st)  28-30 transmission_specular.weft[0..2]
    31-33 transmission_forward.warp[0..2] (k_f, the forward band)  34-36 transmission_forward.weft[0..2]

Everything else (pattern, densities, noise level, thickness, yarn width, forward width, seed) comes
from the base parameters and has no gradient. woven.Params(...).vector gives a start."""
import ctypes
import weakref

import numpy as np
import torch

from . import PARAM_NAMES, Params, _int, _text_or_path, scene_info
from ._lib import call, dptr, fptr, lib

__all__ = ["render", "PARAM_NAMES"]


class _Record:
    """A render's per-pixel derivatives, kept in C until the graph that needs them goes."""

    def __init__(self, handle, n, shape):
        self.handle, self.n, self.shape = handle, n, shape
        self._free = weakref.finalize(self, lib.wv_ffi_record_free, handle)

    def vjp(self, dcapture):
        """dL/dtheta (37 doubles) for dL/dcapture, and sum(dcapture * capture)."""
        d = np.ascontiguousarray(dcapture, dtype=np.float32)
        if d.shape != self.shape:
            raise ValueError(f"dL/dcapture of shape {d.shape}, the render's is {self.shape}")
        g, dot = np.empty(len(PARAM_NAMES)), ctypes.c_double()
        call(lib.wv_ffi_record_grad, self.handle, fptr(d), d.size, dptr(g), ctypes.byref(dot))
        return g, dot.value


def _window_shape(scene, window):
    if window is None:
        info = scene_info(scene)
        return None, (info["height"], info["width"], 3)
    w = tuple(_int(v, "window") for v in window)
    if len(w) != 4:
        raise ValueError("window is (x0, y0, width, height)")
    return (ctypes.c_int * 4)(*w), (w[3], w[2], 3)


def _theta(theta):
    t = theta.detach().to("cpu", torch.float64).contiguous().numpy()
    if t.shape != (len(PARAM_NAMES),):
        raise ValueError(f"theta must have {len(PARAM_NAMES)} values (woven.PARAM_NAMES), got shape {tuple(t.shape)}")
    return t


def render_record(theta, params, scene, spp=0, seed=None, threads=0, window=None, precision="float"):
    """The differentiable render in NumPy: (capture, record); record.vjp(dL/dcapture)
    gives (dL/dtheta, sum(dL/dcapture * capture)). theta: NumPy vector or None."""
    if precision not in ("float", "double"):
        raise ValueError(f"precision must be 'float' or 'double', not {precision!r}")
    win, shape = _window_shape(scene, window)
    t = None if theta is None else np.ascontiguousarray(theta, dtype=np.float64)
    if t is not None and t.shape != (len(PARAM_NAMES),):
        raise ValueError(f"theta must have {len(PARAM_NAMES)} values, got shape {t.shape}")
    cap = np.empty(shape, np.float32)
    h = ctypes.c_void_p()
    seed = -1 if seed is None else _int(seed, "seed")
    call(lib.wv_ffi_render_record, _text_or_path(params, "parameters"), dptr(t), _text_or_path(scene, "scene"),
         _int(spp, "spp"), seed, _int(threads, "threads"), precision == "double", win, fptr(cap), cap.size,
         ctypes.byref(h))
    return cap, _Record(h.value, cap.size, shape)


class _Render(torch.autograd.Function):
    @staticmethod
    def forward(ctx, theta, params, scene, spp, seed, threads, window, precision):
        t = _theta(theta)
        if not ctx.needs_input_grad[0] and window is None and precision == "float":
            # no gradient wanted: the plain render (the same image, nothing kept)
            shape = _window_shape(scene, None)[1]
            cap = np.empty(shape, np.float32)
            call(lib.wv_ffi_render, _text_or_path(params, "parameters"), dptr(t), _text_or_path(scene, "scene"),
                 _int(spp, "spp"), -1 if seed is None else _int(seed, "seed"), _int(threads, "threads"), fptr(cap),
                 None, cap.size)
            ctx.record = None
        else:
            cap, ctx.record = render_record(t, params, scene, spp, seed, threads, window, precision)
        return torch.from_numpy(cap).to(theta.dtype)

    @staticmethod
    @torch.autograd.function.once_differentiable
    def backward(ctx, grad_out):
        g, _ = ctx.record.vjp(grad_out.detach().to("cpu").numpy())
        dtheta = torch.from_numpy(g).to(grad_out.dtype)
        return (dtheta,) + (None,) * 7


def render(theta, params, scene="cylinder", spp=0, seed=None, threads=0, window=None, precision="float"):
    """Renders the capture (height x width x 3, theta's dtype, values of the library's
    float image: equal to woven.render(...).capture) of the base parameters params
    (a dict, path or woven.Params) with the continuous parameters replaced by theta.

    backward gives dL/dtheta exactly for the incoming dL/dcapture (the
    vector-Jacobian product of woven's analytic gradient; one pass over the derivatives
    the forward render kept, about 200 bytes a pixel). window=(x0, y0, width, height):
    only that part of the scene's image (the falloff mask stays centred on the whole
    image). precision="double": shade and differentiate in double (gradient checks);
    the image is then the double result rounded to float."""
    if not isinstance(theta, torch.Tensor):
        raise TypeError("theta must be a torch.Tensor")
    if not theta.is_floating_point():
        raise TypeError(f"theta must be a floating-point tensor, not {theta.dtype}")
    if isinstance(params, Params):
        params = params.json
    return _Render.apply(theta, params, scene, spp, seed, threads, None if window is None else tuple(window),
                         precision)
