"""Build of ssw's compiled chain step (the rest of the package is in pyproject.toml).

``ssw/chain/_step.c`` is a plain shared library (no Python C-API) that
:mod:`ssw.chain.kernel` loads through ctypes; the hash of the source is built into it, so
that a library older than its source is refused rather than used. GCC and Clang (Linux,
macOS, MinGW) and MSVC (Windows) build it, each with the flags of :data:`FLAGS`.
"""

import hashlib
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

SOURCE = "ssw/chain/_step.c"  # relative: setuptools wants it so
DIGEST = hashlib.sha256((Path(__file__).parent / SOURCE).read_bytes()).hexdigest()[:16]

#: Compiler flags by setuptools' compiler type. IEEE arithmetic, each operation rounded on
#: its own: no fused multiply-add (GCC and Clang: -ffp-contract=off; MSVC's /fp:precise
#: contracts nothing from Visual Studio 2022 on, and the source's `#pragma fp_contract(off)`
#: covers older ones: /fp:contract must not be given), no -ffast-math (the step tests NaN
#: and signed zeros). -O3 (GCC, Clang) and /O2 (MSVC): the loops vectorized.
UNIX = ["-O3", "-fno-fast-math", "-ffp-contract=off"]
FLAGS = {"unix": UNIX, "mingw32": UNIX, "cygwin": UNIX, "msvc": ["/O2", "/fp:precise"]}


class BuildStep(build_ext):
    """``build_ext`` for a plain shared library: the flags of its compiler, and no Python
    module to export (on Windows setuptools would export ``PyInit__step``, which the file
    does not define; its functions carry ``__declspec(dllexport)`` themselves)."""

    def build_extensions(self) -> None:
        kind = self.compiler.compiler_type
        if kind not in FLAGS:
            raise RuntimeError(f"ssw's chain step: no flags for the compiler type {kind!r} "
                               f"(setup.py knows {sorted(FLAGS)})")
        for ext in self.extensions:
            ext.extra_compile_args = [*FLAGS[kind], *ext.extra_compile_args]
        super().build_extensions()

    def get_export_symbols(self, ext: Extension) -> list[str]:
        return ext.export_symbols


if __name__ == "__main__":  # how pip, uv and setuptools' build backend run this file
    setup(
        cmdclass={"build_ext": BuildStep},
        ext_modules=[
            Extension(
                "ssw.chain._step",
                [SOURCE],
                # a bare token, made a string in the source (no quotes on a command line)
                define_macros=[("SSW_STEP_SOURCE", DIGEST)],
            )
        ],
    )
