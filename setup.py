"""Build of ssw's compiled chain step (the rest of the package is in pyproject.toml).

``ssw/chain/_step.c`` is a plain shared library (no Python C-API) that
:mod:`ssw.chain.kernel` loads through ctypes; the hash of the source is built into it, so
that a library older than its source is refused rather than used.
"""

import hashlib
from pathlib import Path

from setuptools import Extension, setup

SOURCE = "ssw/chain/_step.c"
DIGEST = hashlib.sha256(Path(SOURCE).read_bytes()).hexdigest()[:16]

setup(
    ext_modules=[
        Extension(
            "ssw.chain._step",
            [SOURCE],
            define_macros=[("SSW_STEP_SOURCE", f'"{DIGEST}"')],
            # IEEE arithmetic (no -ffast-math: the step tests NaN and signed zeros)
            extra_compile_args=["-O2", "-fno-fast-math"],
        )
    ]
)
