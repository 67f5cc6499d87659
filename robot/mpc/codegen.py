"""Compile a CasADi function to C once, cache the shared library, fall back cleanly.

``compiled(f)`` generates C for ``f`` (``casadi.Function.generate``), names the
library by the SHA-256 of the C source and the compiler command, and builds it
with ``gcc``/``cc`` into the user cache directory (``$MPCSHARE_CACHE`` or
``$XDG_CACHE_HOME/mpcshare/casadi`` or ``~/.cache/mpcshare/casadi``; never the
repository).  A later process with the same function finds the library and
only loads it.  Writes are atomic (compile to a temporary name, then rename),
so concurrent processes cannot load a half-written file.  When no compiler is
found, compilation fails or the cache is not writable, it returns the
original function (the CasADi virtual machine, slower but identical) and the
reason.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
from pathlib import Path

import casadi as ca

CFLAGS = ("-O2", "-fPIC", "-shared")


def cache_dir() -> Path:
    """Folder of the compiled libraries (see the module docstring)."""
    if os.environ.get("MPCSHARE_CACHE"):
        return Path(os.environ["MPCSHARE_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "mpcshare" / "casadi"


def find_compiler() -> str | None:
    """``$CC`` if set and found, else gcc, else cc; None without a C compiler."""
    for name in (os.environ.get("CC"), "gcc", "cc"):
        if name and shutil.which(name):
            return shutil.which(name)
    return None


def compiled(f: ca.Function, enable: bool = True, timeout_s: float = 120.0) -> tuple[ca.Function, str]:
    """(function, how): the compiled ``f`` (``how`` = "compiled: <path>") or ``f`` itself and why not."""
    if not enable:
        return f, "virtual machine: code generation disabled"
    compiler = find_compiler()
    if compiler is None:
        return f, "virtual machine: no C compiler found (set CC or install gcc)"
    try:
        with tempfile.TemporaryDirectory() as tmp:
            source_name = f"{f.name()}.c"
            cg = ca.CodeGenerator(source_name, {"with_header": False})
            cg.add(f)
            cg.generate(tmp + os.sep)  # the prefix is the folder: no change of the working directory
            source = (Path(tmp) / source_name).read_bytes()
            key = hashlib.sha256(source + " ".join((os.path.basename(compiler),) + CFLAGS).encode()).hexdigest()[:20]
            folder = cache_dir()
            library = folder / f"{f.name()}_{key}.so"
            if not library.exists():
                folder.mkdir(parents=True, exist_ok=True)
                partial = folder / f".{library.name}.{os.getpid()}.tmp"
                result = subprocess.run([compiler, *CFLAGS, "-o", str(partial), str(Path(tmp) / source_name)],
                                        check=False, capture_output=True, text=True, timeout=timeout_s)
                if result.returncode != 0:
                    partial.unlink(missing_ok=True)
                    return f, f"virtual machine: {compiler} failed: {result.stderr.strip()[:300]}"
                os.replace(partial, library)
        return ca.external(f.name(), str(library)), f"compiled: {library}"
    except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
        return f, f"virtual machine: code generation failed ({type(exc).__name__}: {exc})"
