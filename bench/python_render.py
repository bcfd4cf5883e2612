"""Overhead of woven.torch.render over the same C calls made directly (libwoven.so's flat
interface through ctypes, in one process): forward alone, forward with the derivative
record, and forward + backward, at 512 x 512 (the flat45 rig), 4 spp, 2 threads.
Prints JSON: the median milliseconds of each and the overhead (the median over pairs, run
in turn, of torch / C, minus 1).

    PYTHONPATH=python WOVEN_LIBRARY=build/libwoven.so /usr/bin/python3 bench/python_render.py [--reps N]
"""
import argparse
import ctypes
import json
import statistics
import time
from pathlib import Path

import numpy as np
import torch

import woven
import woven.torch as wt
from woven._lib import call, dptr, fptr, lib

ROOT = Path(__file__).resolve().parents[1]


def ms(fn):
    t0 = time.perf_counter()
    fn()
    return (time.perf_counter() - t0) * 1e3


def paired(c_fn, t_fn, reps):
    """The C call and the torch call in turn, reps pairs after a warm-up of each: the
    median of each and the median of the per-pair ratios, which holds when the machine's
    speed drifts."""
    c_fn(), t_fn()  # warm up (first touch of the buffers, thread pool)
    c, t = [], []
    for _ in range(reps):
        c.append(ms(c_fn))
        t.append(ms(t_fn))
    return statistics.median(c), statistics.median(t), statistics.median(b / a for a, b in zip(c, t))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=15)
    ap.add_argument("--params", default=str(ROOT / "examples/twill.json"))
    ap.add_argument("--scene", default="flat45")
    ap.add_argument("--spp", type=int, default=4)
    ap.add_argument("--threads", type=int, default=2)
    a = ap.parse_args()
    base = woven.Params(a.params)
    info = woven.scene_info(a.scene)
    shape = (info["height"], info["width"], 3)
    pj, sj = base.json.encode(), a.scene.encode()
    theta_np = base.vector
    adjoint = np.full(shape, 1e-3, np.float32)
    cap = np.empty(shape, np.float32)
    grad = np.empty(len(woven.PARAM_NAMES))

    def c_forward():
        call(lib.wv_ffi_render, pj, dptr(theta_np), sj, a.spp, -1, a.threads, fptr(cap), None, cap.size)

    def c_record(backward):
        h = ctypes.c_void_p()
        call(lib.wv_ffi_render_record, pj, dptr(theta_np), sj, a.spp, -1, a.threads, 0, None, fptr(cap), cap.size,
             ctypes.byref(h))
        if backward:
            call(lib.wv_ffi_record_grad, h, fptr(adjoint), adjoint.size, dptr(grad), None)
        lib.wv_ffi_record_free(h)

    theta = torch.tensor(theta_np, dtype=torch.float32)
    theta_g = theta.clone().requires_grad_(True)
    adjoint_t = torch.from_numpy(adjoint)

    def t_forward():
        with torch.no_grad():
            wt.render(theta, base, a.scene, spp=a.spp, threads=a.threads)

    def t_record():
        wt.render(theta_g, base, a.scene, spp=a.spp, threads=a.threads)

    def t_both():
        theta_g.grad = None
        img = wt.render(theta_g, base, a.scene, spp=a.spp, threads=a.threads)
        img.backward(adjoint_t)

    res = {"width": shape[1], "height": shape[0], "spp": a.spp, "threads": a.threads, "reps": a.reps}
    for name, c_fn, t_fn in (("forward", c_forward, t_forward),
                             ("forward_record", lambda: c_record(False), t_record),
                             ("forward_backward", lambda: c_record(True), t_both)):
        c_ms, t_ms, ratio = paired(c_fn, t_fn, a.reps)
        res[name] = {"c_ms": round(c_ms, 3), "torch_ms": round(t_ms, 3), "overhead": round(ratio - 1, 4)}
    print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
