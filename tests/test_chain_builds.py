"""The compiled chain step gives the same bits whatever builds it.

The step's C (``ssw/chain/_step.c``) rounds every IEEE operation on its own, in the order
written: no fused multiply-add (contraction off in ``setup.py``'s flags and, for the
compilers that take one, by a pragma in the source), the far law's SIMD lanes (AVX2, SSE2)
and its scalar path the same operations. So a build by another compiler, for a CPU with
FMA, or on another path must give the installed build's results to the last bit. Each test
here builds the file with ``clang`` or ``gcc`` (``-Wall -Wextra -Werror``: it builds
without a warning), loads it through the package's own loader (:func:`ssw.chain.kernel.
load`: its hash, constants and struct layout checked), makes it the step of every chain run,
and compares, bit by bit, with the installed build (GCC, ``setup.py``'s flags, the CPU's
lanes): the far and near Hertz law at 1003 contacts (edge cases included: zeros of both
signs, infinities, NaN, a zero |delta|), the TOFs of 40 moduli on the Hertz wall and of 5 on
the ``fem`` wall (the law evaluated in the step, blocks of steps per call), the TOF
derivatives and the sensor signal with its sensitivities, runs with each dissipation law,
a preload and all six parameters' tangents, and the step's power law (its Hertzian form,
and ``pow`` and ``log`` for other exponents) at the same 1003 indentations.

The comparison can fail: Clang with ``-ffp-contract=fast`` (which overrides the source's
pragma) and ``-march=haswell`` fuses multiply-adds, and its results must differ from the
installed build's, by rounding only (TOFs within 1e-6 relative).

Builds for ``-march=haswell`` run only on a CPU with AVX2 and FMA. Without clang the tests
skip, and fail with ``CI=true`` (``.ci/run`` installs it).
"""

from __future__ import annotations

import ctypes
import platform
import re
import runpy
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from ssw.chain import kernel
from ssw.chain.integrate import simulate
from ssw.chain.kernel import averaged_hertz
from ssw.chain.params import ChainParams
from ssw.chain.sensitivity import PARAMETERS
from ssw.tof import api
from ssw.walls import build_wall

ROOT = Path(__file__).resolve().parents[1]
HASWELL = "-march=haswell"
SCALAR = "-DSSW_SCALAR"
SSE2 = "-DSSW_NO_AVX2"


def _setup_flags() -> list[str]:
    """``setup.py``'s flags for GCC and Clang (what the package's build uses)."""
    if not (ROOT / "setup.py").exists():
        pytest.skip("no setup.py beside the tests (an installed package): nothing to build")
    return list(runpy.run_path(str(ROOT / "setup.py"), run_name="setup_flags")["FLAGS"]["unix"])


def _cpu_flags() -> set[str]:
    info = Path("/proc/cpuinfo")
    if platform.machine().lower() != "x86_64" or not info.exists():
        return set()
    return {f for line in info.read_text().splitlines() if line.startswith("flags")
            for f in line.split(":", 1)[1].split()}


def _build(cc: str, flags: list[str], out: Path) -> ctypes.CDLL:
    """``_step.c`` built by ``cc`` with ``flags``, loaded by the package's loader."""
    from conftest import require

    require(shutil.which(cc) is not None, f"no {cc} to build the chain step with")
    if HASWELL in flags and not {"avx2", "fma"} <= _cpu_flags():
        pytest.skip(f"this CPU cannot run a {HASWELL} build (no AVX2 and FMA)")
    if SCALAR not in flags and platform.machine().lower() != "x86_64":
        pytest.skip("the SIMD lanes are x86-64's")
    cmd = [cc, "-shared", "-fPIC", "-Wall", "-Wextra", "-Werror", *flags,
           f"-DSSW_STEP_SOURCE={kernel.source_digest()}", str(kernel.SOURCE), "-o", str(out),
           "-lm"]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=600, check=False)
    assert done.returncode == 0, f"{' '.join(cmd)}\n{done.stderr}"
    return kernel.load(out)


def _fingerprint() -> dict[str, np.ndarray]:
    """What the step computes, through the public paths: the Hertz law, TOFs, derivatives,
    signals."""
    out = {}
    rng = np.random.default_rng(3)
    a = rng.uniform(1e-9, 1e-6, 1003)
    x = np.concatenate([rng.uniform(-2.0, 25.0, 900), rng.uniform(20.0, 1e4, 90),
                        [-1.0, 0.0, -0.0, 1.0, 20.0, np.nextafter(20.0, 0.0), np.inf, -np.inf,
                         np.nan, 1e300, -1e-300, 5e-324, 0.5]])
    d = x * a
    a[-5:] = [0.0, 0.0, np.inf, 1e-300, -0.0]
    out["hertz"] = np.stack(averaged_hertz(d, a, 1.2e10, tangent=True))
    p = ChainParams()
    E = np.geomspace(10e6, 1000e6, 40)
    out["tof_hertz"] = api.tof(E, 0.3, p)
    out["tof_fem"] = api.tof(E[::8], 0.3, p, "fem")
    der = api.tof_derivatives(E[::10], 0.3, p)
    out["dtof"] = np.stack([der.tof, *(der.dtof[k] for k in sorted(der.dtof))])
    out["sensor"], out["dsensor"] = der.run.sensor, der.run.dsensor
    for law, c in (("kuwabara_kono", 3e3), ("hunt_crossley", 0.05), ("dashpot", 2.0)):
        q = ChainParams(damping=c, damping_law=law, preload=2.0)
        w = build_wall("hertz", q, E[::13], np.full(E[::13].size, 0.3))
        run = simulate(q, w, derivatives=tuple(PARAMETERS))
        out[f"{law}_sensor"], out[f"{law}_dsensor"] = run.sensor, run.dsensor
    # the step's power law: its Hertzian form, and pow and log for other exponents
    e = np.where(np.arange(d.size) % 2, 1.5, rng.uniform(1.0, 3.0, d.size))
    law = (rng.uniform(1e9, 1e11, d.size), e, rng.normal(0.0, 10.0, d.size),
           rng.normal(0.0, 1e-9, d.size))
    out["power_law"] = np.stack(kernel.power_law(law, d, tangent=True, with_E=True))
    out["power_law_hertz"] = np.stack(
        kernel.power_law((law[0], np.full(d.size, 1.5), *law[2:]), d, tangent=True,
                         with_E=True))
    return out


def _differing(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> list[str]:
    """The entries whose shapes or bits differ."""
    assert a.keys() == b.keys()
    return [k for k in a if a[k].shape != b[k].shape
            or not np.array_equal(a[k].view(np.uint64), b[k].view(np.uint64))]


@pytest.fixture(scope="module")
def installed() -> dict[str, np.ndarray]:
    """The installed build's fingerprint."""
    return _fingerprint()


def _with(lib: ctypes.CDLL, monkeypatch: pytest.MonkeyPatch) -> dict[str, np.ndarray]:
    """The fingerprint with ``lib`` as the step of every run."""
    monkeypatch.setattr(kernel, "library", lambda: lib)
    return _fingerprint()


def _case(name: str, cc: str, extra: list[str], lanes: int, slow: bool = False,
          contract: bool = True):
    return pytest.param(cc, extra, lanes, contract, id=name,
                        marks=[pytest.mark.slow] if slow else [])


@pytest.mark.parametrize(("cc", "extra", "lanes", "contract"), [
    # Clang on a CPU with FMA: setup.py's flags keep it from fusing
    _case("clang-haswell", "clang", [HASWELL], 4),
    # the scalar path (arm64 and any CPU but x86-64's)
    _case("gcc-scalar", "gcc", [SCALAR], 1),
    _case("clang", "clang", [], 4, slow=True),
    # without -ffp-contract=off: the source's pragmas alone (Clang's STDC FP_CONTRACT, GCC's
    # optimize; GCC fuses by default in GNU C)
    _case("clang-haswell-pragma", "clang", [HASWELL], 4, slow=True, contract=False),
    _case("gcc-haswell-pragma", "gcc", [HASWELL], 4, slow=True, contract=False),
    _case("clang-scalar-haswell", "clang", [SCALAR, HASWELL], 1, slow=True),
    # the SSE2 lanes of a CPU without AVX2
    _case("gcc-sse2", "gcc", [SSE2], 2, slow=True),
])
def test_another_build_gives_the_same_bits(cc, extra, lanes, contract, installed, tmp_path,
                                           monkeypatch):
    """A build by ``cc`` with setup.py's flags and ``extra`` (``contract``: with
    ``-ffp-contract=off``) gives every array of the fingerprint to the last bit, on its
    lanes (4 AVX2, 2 SSE2, 1 scalar)."""
    flags = [f for f in _setup_flags() if contract or f != "-ffp-contract=off"]
    lib = _build(cc, flags + extra, tmp_path / "_step.so")
    if lanes == 4 and "avx2" not in _cpu_flags():
        lanes = 2
    assert lib.ssw_step_lanes() == lanes
    assert _differing(installed, _with(lib, monkeypatch)) == []


def test_a_build_that_fuses_multiply_adds_differs(installed, tmp_path, monkeypatch):
    """The comparison's own check: Clang with ``-ffp-contract=fast`` (contraction across
    statements, the source's pragma overridden) on ``-march=haswell`` fuses multiply-adds;
    its Hertz law, TOFs and signals then differ from the installed build's in their last
    bits (TOFs by at most 1e-6 relative: rounding, not another computation)."""
    flags = [f for f in _setup_flags() if f != "-ffp-contract=off"]
    lib = _build("clang", [*flags, "-ffp-contract=fast", HASWELL], tmp_path / "_step.so")
    fused = _with(lib, monkeypatch)
    assert {"hertz", "tof_hertz", "sensor", "dsensor"} <= set(_differing(installed, fused))
    np.testing.assert_allclose(fused["tof_hertz"], installed["tof_hertz"], rtol=1e-6)


#: MSVC's headers as far as ``_step.c`` uses them, prototypes only (the MSVC branch's
#: syntax check below: the intrinsics, CPUID, XGETBV and the C library's few functions).
MSVC_STUBS = {
    "immintrin.h": """
typedef struct { double v[4]; } __m256d;
typedef struct { double v[2]; } __m128d;
#define _CMP_LT_OS 1
#define _CMP_GT_OS 14
#define V4(f, ...) __m256d _mm256_##f(__VA_ARGS__);
#define V2(f, ...) __m128d _mm_##f(__VA_ARGS__);
V4(set1_pd, double) V4(loadu_pd, const double *) V4(add_pd, __m256d, __m256d)
V4(sub_pd, __m256d, __m256d) V4(mul_pd, __m256d, __m256d) V4(div_pd, __m256d, __m256d)
V4(sqrt_pd, __m256d) V4(and_pd, __m256d, __m256d) V4(andnot_pd, __m256d, __m256d)
V4(or_pd, __m256d, __m256d) V4(cmp_pd, __m256d, __m256d, const int)
V2(set1_pd, double) V2(loadu_pd, const double *) V2(add_pd, __m128d, __m128d)
V2(sub_pd, __m128d, __m128d) V2(mul_pd, __m128d, __m128d) V2(div_pd, __m128d, __m128d)
V2(sqrt_pd, __m128d) V2(and_pd, __m128d, __m128d) V2(andnot_pd, __m128d, __m128d)
V2(or_pd, __m128d, __m128d) V2(cmpgt_pd, __m128d, __m128d) V2(cmplt_pd, __m128d, __m128d)
void _mm256_storeu_pd(double *, __m256d); void _mm_storeu_pd(double *, __m128d);
int _mm256_movemask_pd(__m256d); int _mm_movemask_pd(__m128d); void _mm256_zeroupper(void);
unsigned __int64 _xgetbv(unsigned int);
""",
    "intrin.h": "void __cpuidex(int info[4], int leaf, int sub);\n",
    "math.h": "double sqrt(double); double fabs(double); double pow(double, double);\n"
              "double log(double);\n#define isinf(x) __builtin_isinf(x)\n",
    "string.h": "void *memcpy(void *, const void *, unsigned __int64);\n"
                "void *memset(void *, int, unsigned __int64);\n",
}


def test_the_msvc_branch_parses(tmp_path):
    """No MSVC here: this is Clang reading ``_step.c`` as MSVC would see it (the Windows
    x64 target's macros, ``_MSC_VER`` and ``_M_X64``, Microsoft's extensions, not
    ``__clang__``), against prototypes of the intrinsics and C functions it calls
    (:data:`MSVC_STUBS`), without a warning but for MSVC's own ``#pragma fp_contract``:
    the MSVC-only lines (``__declspec(dllexport)``, ``__forceinline``, ``__declspec(
    noinline)``, ``__cpuidex``, ``_xgetbv``, ``DllMain``, the intrinsics' lanes and
    ``_mm256_zeroupper``) parse and type-check, and every function is exported."""
    from conftest import require

    require(shutil.which("clang") is not None, "no clang to read the MSVC branch with")
    for name, text in MSVC_STUBS.items():
        (tmp_path / name).write_text(text)
    cmd = ["clang", "--target=x86_64-pc-windows-msvc", "-fms-extensions", "-fms-compatibility",
           "-U__clang__", "-Wall", "-Wextra", "-Werror", "-Wno-unknown-pragmas",
           f"-I{tmp_path}", str(kernel.SOURCE)]
    done = subprocess.run([*cmd, "-fsyntax-only"], capture_output=True, text=True,
                          timeout=300, check=False)
    assert done.returncode == 0, done.stderr
    text = subprocess.run([*cmd, "-E"], capture_output=True, text=True, timeout=300,
                          check=True).stdout
    assert "int __stdcall DllMain(" in text and "__cpuidex(x," in text
    exported = re.findall(r"__declspec\(dllexport\) [\w ]+?\**(ssw_\w+)\(", text)
    # the same functions as the installed build exports (its ELF dynamic symbols)
    require(shutil.which("nm") is not None, "no nm to list the installed build's exports")
    so = kernel.library()._name
    nm = subprocess.run(["nm", "-D", "--defined-only", so], capture_output=True, text=True,
                        timeout=60, check=True).stdout
    elf = [line.split()[-1] for line in nm.splitlines() if line.split()[-1].startswith("ssw_")]
    assert elf and sorted(exported) == sorted(elf)

