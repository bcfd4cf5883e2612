"""Loads libwoven.so and declares the flat C interface of include/woven/ffi.h (ctypes)."""
import ctypes
import ctypes.util
import os
from pathlib import Path

ABI_VERSION = 1  # WV_FFI_VERSION this package was written for

_F = ctypes.POINTER(ctypes.c_float)
_D = ctypes.POINTER(ctypes.c_double)
_I = ctypes.POINTER(ctypes.c_int)
_S = ctypes.c_char_p
_Z = ctypes.c_size_t
_ERR = [ctypes.c_char_p, ctypes.c_size_t]  # every call's message buffer

_SIGNATURES = {
    "wv_ffi_version": (ctypes.c_int, []),
    "wv_ffi_param_count": (ctypes.c_int, []),
    "wv_ffi_param_name": (ctypes.c_char_p, [ctypes.c_int]),
    "wv_ffi_param_range": (ctypes.c_int, [ctypes.c_int, _D, _D]),
    "wv_ffi_params_json": (ctypes.c_int, [_S, _D, ctypes.c_char_p, _Z] + _ERR),
    "wv_ffi_params_default": (ctypes.c_int, [_S, ctypes.c_char_p, _Z] + _ERR),
    "wv_ffi_params_vector": (ctypes.c_int, [_S, _D] + _ERR),
    "wv_ffi_scene_info": (ctypes.c_int, [_S, _I, _I, _I, _D] + _ERR),
    "wv_ffi_scene_capture": (ctypes.c_int, [_S, _F, ctypes.c_int, ctypes.c_int, _F, _Z] + _ERR),
    "wv_ffi_render": (ctypes.c_int, [_S, _D, _S, ctypes.c_int, ctypes.c_longlong, ctypes.c_int, _F, _F, _Z] + _ERR),
    "wv_ffi_render_record": (ctypes.c_int, [_S, _D, _S, ctypes.c_int, ctypes.c_longlong, ctypes.c_int, ctypes.c_int,
                                            _I, _F, _Z, ctypes.POINTER(ctypes.c_void_p)] + _ERR),
    "wv_ffi_record_grad": (ctypes.c_int, [ctypes.c_void_p, _F, _Z, _D, _D] + _ERR),
    "wv_ffi_record_free": (None, [ctypes.c_void_p]),
    "wv_ffi_map_name": (ctypes.c_char_p, [ctypes.c_int]),
    "wv_ffi_maps": (ctypes.c_int, [_S, ctypes.c_int, _F, _Z, _D, _D] + _ERR),
    "wv_ffi_maps_write": (ctypes.c_int, [_S, ctypes.c_int, _S, _S] + _ERR),
    "wv_ffi_image_size": (ctypes.c_int, [_S, _I, _I] + _ERR),
    "wv_ffi_image_read": (ctypes.c_int, [_S, _F, _Z] + _ERR),
    "wv_ffi_image_write": (ctypes.c_int, [_S, _F, ctypes.c_int, ctypes.c_int] + _ERR),
    "wv_ffi_compare": (ctypes.c_int, [_F, _F, ctypes.c_int, ctypes.c_int, ctypes.c_double, ctypes.c_int, _D] + _ERR),
    "wv_ffi_env_builtin": (ctypes.c_int, [_S, ctypes.c_int, _F, _Z] + _ERR),
    "wv_ffi_capture": (ctypes.c_int, [_S, _S, _S, _S, ctypes.c_char_p, _Z] + _ERR),
}


class WovenError(Exception):
    """A failure reported by woven: .status is its wv_status code (2 invalid value,
    3 I/O, 4 malformed file, 5 too large, 6 internal), str() its message."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


def _candidates():
    env = os.environ.get("WOVEN_LIBRARY")
    if env:
        yield Path(env)
        return
    here = Path(__file__).resolve().parent
    yield here / "libwoven.so"
    # a source checkout: python/woven/ beside build/
    for up in here.parents:
        yield up / "build" / "libwoven.so"
        if (up / ".git").exists():
            break
    found = ctypes.util.find_library("woven")
    if found:
        yield Path(found)


def _load():
    tried = []
    for path in _candidates():
        tried.append(str(path))
        if path.is_absolute() and not path.exists():
            continue
        try:
            lib = ctypes.CDLL(str(path))
        except OSError:
            continue
        if not hasattr(lib, "wv_ffi_version"):
            continue
        for name, (res, args) in _SIGNATURES.items():
            fn = getattr(lib, name)
            fn.restype, fn.argtypes = res, args
        if lib.wv_ffi_version() != ABI_VERSION:
            raise ImportError(f"{path}: woven's interface version {lib.wv_ffi_version()}, "
                              f"this package needs {ABI_VERSION}")
        return lib
    raise ImportError("libwoven.so not found (build it with `cmake --build build --target woven_shared`, "
                      "then set WOVEN_LIBRARY=/path/to/build/libwoven.so); tried: " + ", ".join(tried))


lib = _load()


def call(fn, *args):
    """Calls a woven function whose last two arguments are the message buffer; raises
    WovenError with woven's message on failure."""
    err = ctypes.create_string_buffer(1024)
    st = fn(*args, err, len(err))
    if st:
        raise WovenError(st, err.value.decode("utf-8", "replace"))


def fptr(a):
    return a.ctypes.data_as(_F) if a is not None else None


def dptr(a):
    return a.ctypes.data_as(_D) if a is not None else None
