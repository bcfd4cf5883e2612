"""woven from Python: render fabric parameters in a capture scene, texture maps, image
metrics and the whole photo capture, over libwoven.so's flat C interface
(include/woven/ffi.h). woven.torch adds a differentiable render for PyTorch.

Images are NumPy arrays of shape (height, width, 3), float32, top row first."""
import json
import operator
import os
from typing import NamedTuple

import numpy as np

from ._lib import WovenError, call, dptr, fptr, lib
import ctypes

__all__ = ["WovenError", "Params", "Render", "PARAM_NAMES", "MAP_NAMES", "param_range", "scene_info",
           "render", "maps", "write_maps", "compare", "capture", "read_image", "write_image", "to_png8",
           "scene_capture", "environment"]

PARAM_NAMES = tuple(lib.wv_ffi_param_name(i).decode() for i in range(lib.wv_ffi_param_count()))
"""The continuous parameters in the order of every parameter vector (woven/params.h wv_param_id)."""
MAP_NAMES = tuple(lib.wv_ffi_map_name(i).decode() for i in range(9))

_JSON_MAX = 1 << 20  # a parameter file as JSON text is a few kB


def param_range(name_or_index):
    """(lo, hi) of a continuous parameter, in the parameter file's units."""
    i = PARAM_NAMES.index(name_or_index) if isinstance(name_or_index, str) else operator.index(name_or_index)
    lo, hi = ctypes.c_double(), ctypes.c_double()
    if lib.wv_ffi_param_range(i, ctypes.byref(lo), ctypes.byref(hi)):
        raise IndexError(f"no parameter {name_or_index!r}")
    return lo.value, hi.value


def _text_or_path(x, what):
    """JSON text (dict) or a path, as bytes for the C side."""
    if isinstance(x, Params):
        return x.json.encode()
    if isinstance(x, dict):
        return json.dumps(x).encode()
    if isinstance(x, (str, bytes, os.PathLike)):
        s = os.fsencode(x)
        if not s:
            raise ValueError(f"empty {what}")
        return s
    raise TypeError(f"{what} must be a dict, a woven.Params or a path, not {type(x).__name__}")


def _int(x, name):
    try:
        return operator.index(x)
    except TypeError:
        raise TypeError(f"{name} must be an integer, not {type(x).__name__}") from None


def _vector(theta):
    if theta is None:
        return None
    t = np.ascontiguousarray(theta, dtype=np.float64)
    if t.shape != (len(PARAM_NAMES),):
        raise ValueError(f"a parameter vector has {len(PARAM_NAMES)} values, got shape {t.shape}")
    return t


class Params:
    """Fabric parameters: a parameter file's content, validated by woven.

    Params(x) takes a dict, JSON text, a path to params.json or another Params.
    .data is the dict (as woven writes it), .vector the continuous parameters
    (PARAM_NAMES order), .with_vector(theta) a copy with them replaced."""

    def __init__(self, source, _theta=None):
        src = _text_or_path(source, "parameters")
        buf = ctypes.create_string_buffer(_JSON_MAX)
        call(lib.wv_ffi_params_json, src, dptr(_vector(_theta)), buf, len(buf))
        self.json = buf.value.decode()
        self.data = json.loads(self.json)

    @classmethod
    def default(cls, pattern):
        """A built-in pattern's prior mean (plain, twill, satin, ...)."""
        buf = ctypes.create_string_buffer(_JSON_MAX)
        call(lib.wv_ffi_params_default, str(pattern).encode(), buf, len(buf))
        return cls(buf.value.decode())

    load = classmethod(lambda cls, path: cls(os.fspath(path)))

    @property
    def vector(self):
        t = np.empty(len(PARAM_NAMES), np.float64)
        call(lib.wv_ffi_params_vector, self.json.encode(), dptr(t))
        return t

    def with_vector(self, theta):
        return Params(self.json, _theta=theta)

    def save(self, path):
        with open(path, "w") as f:
            f.write(self.json + "\n")

    def __getitem__(self, key):
        return self.data[key]

    def __repr__(self):
        return f"woven.Params({self.json})"


class Render(NamedTuple):
    """woven.render's result: radiance (linear, times the scene's exposure: the CLI's
    EXR), capture (what the scene's camera records, float) and png (capture quantised
    to 8 bits as the CLI's PNG)."""
    radiance: np.ndarray
    capture: np.ndarray
    png: np.ndarray


def scene_info(scene):
    """dict(width, height, spp, exposure) of a capture scene (preset name, path or dict)."""
    w, h, spp, ex = ctypes.c_int(), ctypes.c_int(), ctypes.c_int(), ctypes.c_double()
    call(lib.wv_ffi_scene_info, _text_or_path(scene, "scene"), ctypes.byref(w), ctypes.byref(h),
         ctypes.byref(spp), ctypes.byref(ex))
    return {"width": w.value, "height": h.value, "spp": spp.value, "exposure": ex.value}


def to_png8(image):
    """float image -> uint8 as woven's PNG writer quantises it (clamped to [0, 1])."""
    v = np.asarray(image, dtype=np.float32)
    with np.errstate(invalid="ignore"):
        q = (v * np.float32(255) + np.float32(0.5))
        q = np.where(v >= 1, 255, np.where(v > 0, q, 0))  # NaN -> 0, as the writer
    return q.astype(np.uint8)


def render(params, scene="cylinder", spp=0, seed=None, threads=0):
    """Renders params in a capture scene as `woven render` does; returns a Render
    (radiance, capture, png arrays of height x width x 3). spp 0: the scene's; seed
    None: the parameters' noise seed; threads 0: all cores."""
    p, s = _text_or_path(params, "parameters"), _text_or_path(scene, "scene")
    spp, threads = _int(spp, "spp"), _int(threads, "threads")
    seed = -1 if seed is None else _int(seed, "seed")
    if seed < -1:
        raise ValueError(f"seed {seed} is negative")
    info = scene_info(scene)
    cap = np.empty((info["height"], info["width"], 3), np.float32)
    rad = np.empty_like(cap)
    call(lib.wv_ffi_render, p, None, s, spp, seed, threads, fptr(cap), fptr(rad), cap.size)
    return Render(rad, cap, to_png8(cap))


def scene_capture(scene, radiance):
    """What the scene's camera makes of a radiance image of its size (blur, exposure,
    clip, colour encoding, falloff mask)."""
    r = _image(radiance, "radiance")
    out = np.empty_like(r)
    call(lib.wv_ffi_scene_capture, _text_or_path(scene, "scene"), fptr(r), r.shape[1], r.shape[0], fptr(out), out.size)
    return out


def maps(params, size=1024):
    """The tileable maps of one weave repeat (as `woven maps`): a dict of size x size x 3
    float arrays (normal, tangent, yarn_id, height, diffuse, specular, roughness,
    transmission, open; vectors in [-1, 1], albedos and the transmission linear, open 1 in
    an open gap), plus tile_mm (width, height of the tile) and height_max."""
    size = _int(size, "size")
    if not 1 <= size <= 8192:
        raise ValueError(f"map size {size} is outside 1..8192")
    out = np.empty((len(MAP_NAMES), size, size, 3), np.float32)
    tile, hmax = np.zeros(2), ctypes.c_double()
    call(lib.wv_ffi_maps, _text_or_path(params, "parameters"), size, fptr(out), out.size, dptr(tile),
         ctypes.byref(hmax))
    d = {name: out[i] for i, name in enumerate(MAP_NAMES)}
    d["tile_mm"] = (float(tile[0]), float(tile[1]))
    d["height_max"] = hmax.value
    return d


def write_maps(params, out, size=1024, format="png"):
    """Writes the maps into directory out as `woven maps` does (png, exr or both)."""
    call(lib.wv_ffi_maps_write, _text_or_path(params, "parameters"), _int(size, "size"), os.fsencode(out),
         str(format).encode())


def read_image(path):
    """An image file as woven reads it (8/16-bit scaled to [0, 1], EXR as stored), H x W x 3."""
    p = os.fsencode(path)
    w, h = ctypes.c_int(), ctypes.c_int()
    call(lib.wv_ffi_image_size, p, ctypes.byref(w), ctypes.byref(h))
    out = np.empty((h.value, w.value, 3), np.float32)
    call(lib.wv_ffi_image_read, p, fptr(out), out.size)
    return out


def _image(a, what):
    if isinstance(a, (str, bytes, os.PathLike)):
        return read_image(a)
    arr = np.asarray(a)
    if arr.ndim != 3 or arr.shape[2] != 3 or arr.shape[0] < 1 or arr.shape[1] < 1:
        raise ValueError(f"{what} must be an image of shape (height, width, 3), got {arr.shape}")
    if arr.dtype == np.uint8:  # as woven reads an 8-bit file
        arr = arr.astype(np.float32) / np.float32(255)
    return np.ascontiguousarray(arr, dtype=np.float32)


def write_image(path, image):
    """Writes .png (8-bit, clamped) or .exr (float) as woven does."""
    a = _image(image, "image")
    call(lib.wv_ffi_image_write, os.fsencode(path), fptr(a), a.shape[1], a.shape[0])


def compare(a, b, blur=0.0, channels="luma"):
    """`woven compare`: SSIM (luminance, or channels="rgb"), WSC, whitened WSC (None
    below 32 x 32 pixels) and MAE of two images (arrays or files) of the same size,
    after Gaussian blurs of sigma blur pixels when blur > 0."""
    if channels not in ("luma", "rgb"):
        raise ValueError(f"channels must be 'luma' or 'rgb', not {channels!r}")
    x, y = _image(a, "a"), _image(b, "b")
    if x.shape != y.shape:
        raise ValueError(f"images of different sizes: {x.shape} and {y.shape}")
    out = np.zeros(4)
    call(lib.wv_ffi_compare, fptr(x), fptr(y), x.shape[1], x.shape[0], float(blur), channels == "rgb", dptr(out))
    nan = lambda v: None if np.isnan(v) else float(v)  # noqa: E731
    return {"ssim": float(out[0]), "ssim_channels": channels, "wsc": nan(out[1]), "wsc_whitened": nan(out[2]),
            "mae": float(out[3]), "blur": float(blur)}


def environment(name="studio", width=1024):
    """A built-in environment (studio, sky, white) as an equirectangular width x width/2 image."""
    width = _int(width, "width")
    if not 16 <= width <= 8192:
        raise ValueError(f"environment width {width} is outside 16..8192")
    out = np.empty((width // 2, width, 3), np.float32)
    call(lib.wv_ffi_env_builtin, str(name).encode(), width, fptr(out), out.size)
    return out


def capture(photo, scene, out, **opts):
    """`woven capture`: FabricNet's estimate of the photo, then the fit; every output in
    directory out. opts: pattern, model, descriptor, weights, drape, crop (x, y, w, h),
    iters, iter_spp, iter_scale, seed, threads, align_radius, register_radius,
    distort_degree, force, and for a photo pair transmission (the back-lit photo),
    transmission_scene, pair_model. Returns a dict: pattern, ssim_network, ssim_fit,
    iterations, dir, params (a woven.Params), render (the fit's render.png as an array), and
    as `woven capture --json` names them ssim_rgb_fit, ssim_rgb_blurred_photo,
    below_blurred_copy, wsc_fit, photo_periodic_share (the share of the photo's detail
    that is its weave) and blas_core (OpenBLAS's kernels, which the fit's last digits follow:
    docs/fit.md); for a pair also ssim_rgb_fit_t, ssim_rgb_blurred_photo_t,
    below_blurred_copy_t, photo_periodic_share_t, wsc_fit_t and render_t (the back-lit
    re-render)."""
    if "crop" in opts:
        opts["crop"] = [int(v) for v in opts["crop"]]
    for k in ("transmission", "transmission_scene", "pair_model"):
        if opts.get(k) is not None:
            opts[k] = os.fsdecode(os.fspath(opts[k]))
    buf = ctypes.create_string_buffer(_JSON_MAX)
    call(lib.wv_ffi_capture, os.fsencode(photo), _text_or_path(scene, "scene"), os.fsencode(out),
         json.dumps(opts).encode(), buf, len(buf))
    res = json.loads(buf.value.decode())
    res["params"] = Params(res["params"])
    res["render"] = read_image(os.path.join(os.fsdecode(out), "render.png"))
    if "ssim_rgb_fit_t" in res:
        res["render_t"] = read_image(os.path.join(os.fsdecode(out), "render_t.png"))
    return res
