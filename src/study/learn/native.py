"""The compiled time loops of the recurrent layers (``peephole.cpp``, ``gru.cpp``): built on first use,
loaded with ctypes.

Why: one time step of the layer is one small matrix product and a dozen elementwise operations; as
PyTorch kernels each costs a few microseconds of dispatch, which at batch 32 is most of the training
time. ``peephole.cpp`` does a step's elementwise work in one fused, vectorised loop and hands the
matrix product to PyTorch's own BLAS (``sgemm_``/``dgemm_`` of ``libtorch_cpu``).

The library is compiled with the system C++ compiler (``$CXX``, else ``g++``; about a second, no
PyTorch headers) into a folder keyed by the source, the compiler, the flags and this CPU, written
atomically. Without a compiler, or with ``STUDY_NATIVE=0``, :func:`load` returns ``None`` and
``study.learn.model`` runs the same loop as PyTorch operations (slower; last-bit rounding differs, so the
backend is part of every training run's cache key: :func:`backend`).
"""

from __future__ import annotations

import contextlib
import ctypes
import hashlib
import os
import platform
import shutil
import subprocess
import tempfile
import warnings
from collections.abc import Iterator
from functools import lru_cache
from pathlib import Path

import platformdirs
import torch

_HERE = Path(__file__).resolve().parent
PACKAGE = _HERE.parent
"""The ``study`` package folder."""
SOURCES = (_HERE / "peephole.cpp", _HERE / "gru.cpp")
"""Compiled together into one library; both include ``rnn_math.h``."""
HEADER = _HERE / "rnn_math.h"
FILES = (*SOURCES, HEADER)
"""Every file the library is built from: its build key, and the training runs' cache keys, hash them all."""
FLAGS = ["-O3", "-march=native", "-fno-math-errno", "-fno-trapping-math", "-ffp-contract=fast",
         "-funsafe-math-optimizations", "-ffinite-math-only", "-fschedule-insns", "-fsched-pressure",
         "-fPIC", "-shared", "-std=c++17"] + (["-mrecip=vec-div"] if platform.machine().lower() in ("x86_64", "amd64") else [])
"""Compiler flags. ``-march=native`` lets the loops use this CPU's vector width (hence the CPU in the key).
The unsafe-math pair lets ``-mrecip`` turn the gates' float divisions into a reciprocal estimate plus a
Newton step (about 2x faster forward loop on x86-64; relative error ~1e-7, as the exp); the scheduling
pair interleaves independent units' instructions. Outputs stay within the tests' 1e-5 of float64."""


SIGNATURES: dict[str, int] = {
    "peephole_forward_f32": 9, "peephole_forward_f64": 9, "peephole_backward_f32": 13, "peephole_backward_f64": 13,
    "gru_forward_f32": 7, "gru_forward_f64": 7, "gru_backward_f32": 9, "gru_backward_f64": 9,
}
"""Each entry point of the library and how many pointers it takes after its three ints (T, B, H), the
BLAS routine last; all return nothing. ctypes checks every call against these (see :class:`Native`)."""


class Native:
    """The loaded library: its entry points (per dtype) and the BLAS routine pointers they call.

    Every entry point has its ``argtypes`` and ``restype`` declared from :data:`SIGNATURES`, so a call
    with the wrong number or kind of arguments raises ``TypeError`` or ``ctypes.ArgumentError``
    instead of corrupting memory.
    """

    def __init__(self, lib: ctypes.CDLL, sgemm: int, dgemm: int, build_id: str = "") -> None:
        self.lib = lib  # held so the library stays loaded
        self.build_id = build_id
        for name, n_pointers in SIGNATURES.items():
            fn = getattr(lib, name)
            fn.argtypes = [ctypes.c_int] * 3 + [ctypes.c_void_p] * n_pointers
            fn.restype = None
        self.blas = {torch.float32: ctypes.c_void_p(sgemm), torch.float64: ctypes.c_void_p(dgemm)}
        self.forward = {torch.float32: lib.peephole_forward_f32, torch.float64: lib.peephole_forward_f64}
        self.backward = {torch.float32: lib.peephole_backward_f32, torch.float64: lib.peephole_backward_f64}
        self.gru_forward = {torch.float32: lib.gru_forward_f32, torch.float64: lib.gru_forward_f64}
        self.gru_backward = {torch.float32: lib.gru_backward_f32, torch.float64: lib.gru_backward_f64}


def all_finite(*tensors: torch.Tensor | None) -> bool:
    """Whether every given tensor (``None`` skipped) holds only finite numbers: the compiled loops' contract.

    Tested on each tensor's sum, which a NaN or an infinity makes NaN or infinite: 20x cheaper than
    ``isfinite(t).all()`` (which cost half a training step). A sum of finite numbers that overflows
    answers False too, which only sends that call down the PyTorch path.
    """
    return all(t is None or bool(torch.isfinite(t.sum())) for t in tensors)


def ptr(t: torch.Tensor) -> ctypes.c_void_p:
    """The address of a contiguous tensor's data, as the compiled loops take it."""
    return ctypes.c_void_p(t.data_ptr())


def own(grad: torch.Tensor | None, like: torch.Tensor, shape: tuple[int, ...]) -> torch.Tensor:
    """Our own contiguous copy of an incoming gradient (zeros of ``shape`` where autograd passes None):
    the loops write into it in place, so it must not alias autograd's tensor."""
    return like.new_zeros(shape) if grad is None else grad.clone(memory_format=torch.contiguous_format)


def cache_dir() -> Path:
    """Where compiled libraries live: ``$STUDY_NATIVE_DIR``, else the platform's user cache folder
    (``$XDG_CACHE_HOME/study/native``, by default ``~/.cache/study/native``, on Linux)."""
    env = os.environ.get("STUDY_NATIVE_DIR")
    return Path(env) if env else platformdirs.user_cache_path("study") / "native"


def _cpu() -> str:
    try:
        lines = Path("/proc/cpuinfo").read_text().splitlines()
        return "\n".join(sorted({ln for ln in lines if ln.startswith(("model name", "flags"))}))
    except OSError:
        return platform.processor() or platform.machine()


def _compiler() -> tuple[str, str] | None:
    cxx = shutil.which(os.environ.get("CXX", "g++"))
    if cxx is None:
        return None
    try:
        version = subprocess.run([cxx, "--version"], capture_output=True, text=True, timeout=30).stdout
    except (OSError, subprocess.SubprocessError):
        return None
    return cxx, version


def _blas() -> tuple[int, int] | None:
    """Addresses of PyTorch's own ``sgemm_`` and ``dgemm_`` (Fortran BLAS interface), if exported."""
    lib_dir = Path(torch.__file__).resolve().parent / "lib"
    for name in ("libtorch_cpu.so", "libtorch_cpu.dylib"):
        if (lib_dir / name).is_file():
            try:
                torch_lib = ctypes.CDLL(str(lib_dir / name))
                return (ctypes.cast(torch_lib.sgemm_, ctypes.c_void_p).value,
                        ctypes.cast(torch_lib.dgemm_, ctypes.c_void_p).value)
            except (OSError, AttributeError):
                return None
    return None


def _build_key(version: str) -> str:
    """The library's identity: its sources, the compiler, the flags and this CPU (``-march=native``)."""
    source = b"\0".join(f.read_bytes() for f in FILES)
    return hashlib.sha256(b"\0".join([source, version.encode(), " ".join(FLAGS).encode(), _cpu().encode(),
                                      platform.machine().encode()])).hexdigest()[:16]


def _build(cxx: str, version: str) -> Path:
    target = cache_dir() / f"rnn-{_build_key(version)}.so"
    if target.is_file():
        return target
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(suffix=".so", dir=target.parent)
    os.close(fd)
    try:
        subprocess.run([cxx, *FLAGS, *map(str, SOURCES), "-o", tmp], check=True, capture_output=True, text=True, timeout=300)
        os.replace(tmp, target)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
    return target


@lru_cache(maxsize=1)
def load() -> Native | None:
    """The compiled kernel, building it if needed; ``None`` (with one warning) where it cannot be had."""
    if os.environ.get("STUDY_NATIVE", "1") == "0":
        return None
    blas = _blas()
    compiler = _compiler()
    if blas is None or compiler is None:
        why = "PyTorch's BLAS routines are not exported" if blas is None else "no C++ compiler (set CXX or install g++)"
        warnings.warn(f"recurrent layers: using the slower PyTorch loops: {why}", RuntimeWarning, stacklevel=2)
        return None
    try:
        return Native(ctypes.CDLL(str(_build(*compiler))), *blas, build_id=_build_key(compiler[1]))
    except (OSError, subprocess.SubprocessError) as err:
        detail = getattr(err, "stderr", "") or str(err)
        names = ", ".join(f.name for f in SOURCES)
        warnings.warn(f"recurrent layers: using the slower PyTorch loops: compiling {names} failed: {detail}",
                      RuntimeWarning, stacklevel=2)
        return None


_disabled = False


@contextlib.contextmanager
def disabled() -> Iterator[None]:
    """Within the block ``study.learn.model`` runs the PyTorch loop even where the compiled one exists
    (for benchmarks that compare the two in one run)."""
    global _disabled
    before, _disabled = _disabled, True
    try:
        yield
    finally:
        _disabled = before


def active() -> Native | None:
    """The compiled kernel if it is available and not :func:`disabled`, else ``None``."""
    return None if _disabled else load()


def build_id() -> str:
    """The identity of the compiled library in use (sources, compiler, flags, CPU), or ``''`` on the PyTorch
    loop: part of every training run's cache key, since another CPU's build rounds differently."""
    lib = active()
    return "" if lib is None else lib.build_id


def backend() -> str:
    """``'native'`` when the compiled loop is used, else ``'torch'``: part of training cache keys."""
    return "native" if active() is not None else "torch"
