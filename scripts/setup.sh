#!/usr/bin/env bash
# Set up ssw's environment in .venv: system packages (as root), then a virtual environment
# with the pinned packages of constraints.txt and one PETSc + petsc4py + mpi4py on one MPI.
#
# Two routes to PETSc (the pins say which versions; one PETSc, 3.25.5, by either route):
#   binary  the default where a Python >= 3.12 is on the machine: the dolfinx-solver-real
#           wheel (PETSc, petsc4py, MUMPS, SuperLU_DIST, SLEPc) built against the mpich
#           wheel, which mpi4py's binary wheel loads too; its mpiexec is .venv/bin/mpiexec.
#           Nothing is built; the packages' bytecode is compiled at install (29 s of CPU,
#           49 s of wall time at a load of 7-10, 2 cores; 12 s without the bytecode).
#           PETSc's libraries find the mpich wheel's libmpi.so.12 (in .venv/lib) only once
#           mpi4py has loaded it: scripts/_ssw_petsc_first.py, installed with a .pth line,
#           does that before any import of petsc4py, slepc4py or dolfinx, so that any
#           script run by the venv's Python imports them by itself (0.2-0.4 ms per start).
#   source  SSW_PETSC=source (or no Python >= 3.12 found): PETSc and petsc4py built from
#           their sdists against Debian's MPICH, mpi4py from its sdist against the same
#           mpicc: 15 minutes of CPU (10-13 minutes on 2 quiet cores), once (pip caches the
#           built wheels: 25 s for the next venv).
#
# Environment: SSW_PETSC=binary|source picks the route; SSW_VENV the venv's directory
# (default .venv); SSW_PYTHON the interpreter (default: python3.12/3.13/3.14 on PATH, then
# pyenv's versions, for the binary route; python3.11 for the source route).
#
# Packages are installed by uv (pinned in constraints.txt, put into the venv by pip), the
# source route's three builds by pip (below). Measured on 2 cores from empty caches: the
# whole binary set-up 12 s with uv; its packages alone take 64 s by pip (49 s of CPU
# against uv's 11 s).
#
# Idempotent: a stamp records the hash of this script, constraints.txt, pyproject.toml,
# setup.py, the chain step's C source (ssw/chain/_step.c: a change rebuilds it), the route
# and the interpreter; when nothing changed and the packages are in place, it returns
# in about a second. A venv made by the other route (or another Python) is made anew.
#
# Why the source recipe looks the way it does (measured on this kind of machine):
#   * PETSc's build uses the `mpicc` on PATH and keeps that MPI's RUNPATH in the wheel that
#     pip caches, so MPICH's development package must be installed before it;
#   * petsc4py's isolated build would reuse whatever petsc wheel is cached, so it is built
#     with --no-build-isolation against the petsc just installed in the venv;
#   * the mpi4py binary wheel looks for libmpi.so.12, which Debian's MPICH names
#     libmpich.so.12, so mpi4py is built from source against the same mpicc.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$here"
VENV=${SSW_VENV:-$here/.venv}

log() { printf '[setup] %s\n' "$*" >&2; }
die() { printf 'ssw setup: %s\n' "$*" >&2; exit 1; }

# Up to date: the stamp of this set-up is there and the packages are in place (the full
# import check ran when the stamp was written; this one costs hundredths of a second).
present() {
  "$VENV/bin/python" -c "import importlib.util as u, sys
sys.exit(any(u.find_spec(m) is None
             for m in ('ssw', 'ssw.chain._step', 'gmsh', 'h5py', 'snakemake', 'petsc4py',
                       'mpi4py')))" 2>/dev/null
}
# The full check: ssw's own import of PETSc (the binary stack's MPI first) and mpi4py, and
# its compiled chain step (built from the source in the tree).
check_imports() {
  "$VENV/bin/python" -c "import gmsh, h5py, snakemake, mpi4py
from ssw.chain.kernel import library
library()
from ssw.contact.petsc_solver import _petsc
from mpi4py import MPI
assert _petsc().COMM_WORLD.getSize() == MPI.COMM_WORLD.Get_size()" >/dev/null 2>&1 &&
  # and petsc4py by itself, as a user's own script imports it
  "$VENV/bin/python" -c "from petsc4py import PETSc; PETSc.COMM_WORLD.getSize()" \
    >/dev/null 2>&1
}
# The binary route's start-up hook (scripts/_ssw_petsc_first.py): the mpich wheel's MPI
# loaded before the first import of petsc4py's, slepc4py's or DOLFINx's libraries.
install_petsc_first() {
  local site
  site=$("$VENV/bin/python" -c 'import sysconfig; print(sysconfig.get_path("purelib"))')
  cp scripts/_ssw_petsc_first.py "$site/_ssw_petsc_first.py"
  echo "import _ssw_petsc_first" > "$site/_ssw_petsc_first.pth"
  "$VENV/bin/python" -m compileall -q "$site/_ssw_petsc_first.py" >/dev/null
}
# The stamp of a set-up of this tree for route and Python "$1" (e.g. "binary 3.12.1").
stamp_of() {
  printf '%s/.ssw-setup-%s' "$VENV" "$( (cat scripts/setup.sh scripts/_ssw_petsc_first.py \
    constraints.txt pyproject.toml setup.py ssw/chain/_step.c; echo "$1") |
    sha256sum | cut -c1-16)"
}
# ssw's own bytecode, brought up to date on every call (one process: 0.05 s when it is; a
# pool of workers, -j 0, costs 0.3 s to start and pays only for a full compile)
compile_ssw() { "$VENV/bin/python" -m compileall -q "$@" ssw >/dev/null; }
# ---------------------------------------------------------------- up to date?
# The usual call (`make study`, `make test` on a set-up tree) ends here: the venv records the
# route and Python it was made for (.ssw-route), and the stamp of the set-up that made it is
# there, so no interpreter is looked for (pyenv's shims cost a fifth of a second each).
# Asking for a route or an interpreter (SSW_PETSC, SSW_PYTHON) goes the whole way.
if [ -z "${SSW_PETSC:-}" ] && [ -z "${SSW_PYTHON:-}" ] && [ -f "$VENV/.ssw-route" ] &&
   [ -f "$(stamp_of "$(cat "$VENV/.ssw-route")")" ] && present; then
  compile_ssw
  log "environment up to date ($VENV, $(cat "$VENV/.ssw-route"))"
  exit 0
fi

# ---------------------------------------------------------------- route and interpreter
# A Python >= 3.12 (the binary wheel's floor): $SSW_PYTHON, then on PATH, then pyenv's.
py_ok() { "$1" -c 'import sys; sys.exit(sys.version_info < (3, 12))' >/dev/null 2>&1; }
find_python() {
  local c
  for c in ${SSW_PYTHON:-} python3.12 python3.13 python3.14 \
           "${PYENV_ROOT:-$HOME/.pyenv}"/versions/3.1[2-4]*/bin/python3; do
    if py_ok "$c"; then
      "$c" -c 'import sys; print(sys.executable)'
      return 0
    fi
  done
  return 1
}

ROUTE=${SSW_PETSC:-}
case "$ROUTE" in
  binary)
    PY=$(find_python) || die "SSW_PETSC=binary needs a Python >= 3.12 (set SSW_PYTHON=...)"
    ;;
  source)
    PY=${SSW_PYTHON:-python3.11}
    command -v "$PY" >/dev/null 2>&1 && "$PY" -c '' 2>/dev/null || PY=python3
    ;;
  "")
    if PY=$(find_python); then
      ROUTE=binary
    else
      ROUTE=source
      PY=${SSW_PYTHON:-python3}
      log "no Python >= 3.12 found (SSW_PYTHON, python3.12-3.14, pyenv): building PETSc" \
          "from source (SSW_PETSC=source, about 10-13 minutes on 2 cores)"
    fi
    ;;
  *) die "SSW_PETSC = '$ROUTE' is not allowed: binary (the default) or source" ;;
esac
PYVER=$("$PY" -c 'import sys; print("%d.%d" % sys.version_info[:2])') ||
  die "cannot run the Python interpreter '$PY' (set SSW_PYTHON=...)"

# ---------------------------------------------------------------- system packages
# libglu1-mesa, libxrender1, libxcursor1, libxft2, libxinerama1, libgl1: shared libraries
# the gmsh wheel's libgmsh.so links against even when no window is opened.
# chromium + chromium-driver: the headless browser the report test opens the study report in
# (tests/test_report_browser.py, through selenium; no browser download).
# gcc + libc6-dev: the compiler of ssw's chain step (ssw/chain/_step.c, built by setup.py
# when ssw is installed).
SYS_PKGS=(libglu1-mesa libxrender1 libxcursor1 libxft2 libxinerama1 libgl1 chromium
          chromium-driver gcc libc6-dev)
# source route: libopenblas-dev (BLAS/LAPACK for PETSc), libmpich-dev + mpich (the one MPI:
# mpicc, mpiexec).
if [ "$ROUTE" = source ]; then
  SYS_PKGS+=(libopenblas-dev libmpich-dev mpich)
fi
# A Debian Python without pip needs its venv package (ensurepip) to make a venv with pip.
# (ensurepip is asked first: its import takes hundredths of a second, pip's start ~0.4 s.)
if ! "$PY" -c 'import ensurepip' >/dev/null 2>&1 && ! "$PY" -m pip --version >/dev/null 2>&1
then
  SYS_PKGS+=("python$PYVER-venv")
fi
missing=()
for p in "${SYS_PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  if [ "$(id -u)" = 0 ]; then
    log "installing system packages: ${missing[*]}"
    export DEBIAN_FRONTEND=noninteractive
    apt-get update -qq
    apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  else
    echo "ssw setup: missing system packages: ${missing[*]}" >&2
    echo "install them as root:  sudo apt-get install ${missing[*]}" >&2
    exit 1
  fi
fi
if [ "$ROUTE" = source ]; then
  MPICC=$(command -v mpicc || true)
  if [ -z "$MPICC" ] || ! "$MPICC" -show 2>/dev/null | grep -q mpich; then
    echo "ssw setup: 'mpicc' on PATH must be MPICH's (found: ${MPICC:-none})." >&2
    echo "PETSc, petsc4py and mpi4py must share one MPI; put /usr/bin first on PATH." >&2
    exit 1
  fi
fi

# ---------------------------------------------------------------- virtual environment
id_line="$ROUTE $("$PY" -c 'import sys; print(sys.version.split()[0])')"
stamp=$(stamp_of "$id_line")
if [ -f "$stamp" ] && present; then
  compile_ssw
  log "environment up to date ($VENV, $id_line)"
  exit 0
fi

# a venv of the other route or of another Python is not reused (a second PETSc in the
# binary route's venv is refused by its import guard)
if [ -f "$VENV/pyvenv.cfg" ] && [ "$(cat "$VENV/.ssw-route" 2>/dev/null)" != "$id_line" ]; then
  log "replacing $VENV (made for: $(cat "$VENV/.ssw-route" 2>/dev/null || echo unknown))"
  rm -rf "$VENV"
fi
C=(-c "$here/constraints.txt")
if [ ! -x "$VENV/bin/python" ]; then
  log "creating $VENV ($id_line, $PY)"
  # without ensurepip's pip (seconds) where the interpreter has a pip to install uv with;
  # uv installs the pinned pip with the rest
  if "$PY" -m pip --version >/dev/null 2>&1; then
    "$PY" -m venv --without-pip "$VENV"
  else
    "$PY" -m venv "$VENV"
  fi
  echo "$id_line" > "$VENV/.ssw-route"
fi
if ! "$VENV/bin/uv" --version >/dev/null 2>&1; then
  if "$VENV/bin/python" -m pip --version >/dev/null 2>&1; then
    "$VENV/bin/python" -m pip --disable-pip-version-check -q install "${C[@]}" uv
  else
    "$PY" -m pip --disable-pip-version-check -q --python "$VENV/bin/python" install "${C[@]}" uv
  fi
fi
# Bytecode is compiled at install time (uv's --compile-bytecode, and ssw's own modules by
# compileall below): where PYTHONDONTWRITEBYTECODE is set, nothing would be cached later and
# every job of a study would compile numpy, scipy, matplotlib and ssw again on import.
uvpip() { "$VENV/bin/uv" pip "$1" --quiet --python "$VENV/bin/python" "${@:2}"; }

if [ "$ROUTE" = binary ]; then
  log "installing ssw, its pinned dependencies and the binary PETSc stack"
  uvpip install --compile-bytecode "${C[@]}" pip -e ".[dev,petsc,study]"
  install_petsc_first
else
  # The three builds go through pip, whose wheel cache keeps the built PETSc for the next
  # venv: uv's cache of a registry sdist's build was seen to build PETSc again here.
  uvpip install "${C[@]}" pip numpy cython setuptools wheel
  pip() { "$VENV/bin/python" -m pip --disable-pip-version-check -q "$@"; }
  if ! "$VENV/bin/python" -c "import petsc" >/dev/null 2>&1; then
    log "building PETSc (about 10-13 minutes on 2 cores, once; pip caches the wheel)"
    PETSC_CONFIGURE_OPTIONS="--with-cuda=0 --with-fc=0 --with-x=0 --with-debugging=0" \
      MPICC="$MPICC" pip install "${C[@]}" petsc
  fi
  if ! "$VENV/bin/python" -c "import petsc4py; petsc4py.init(); from petsc4py import PETSc" \
       >/dev/null 2>&1; then
    log "building petsc4py against the venv's PETSc"
    pip install "${C[@]}" --no-build-isolation petsc4py
  fi
  if ! "$VENV/bin/python" -c "from mpi4py import MPI" >/dev/null 2>&1; then
    log "building mpi4py against MPICH"
    MPICC="$MPICC" pip install "${C[@]}" --no-binary=mpi4py mpi4py
  fi
  log "installing ssw and its pinned dependencies"
  uvpip install --compile-bytecode "${C[@]}" -e ".[dev,study]"
fi

check_imports || {
  "$VENV/bin/python" -c "from ssw.contact.petsc_solver import _petsc; _petsc()" || true
  "$VENV/bin/python" -c "from ssw.chain.kernel import library; library()" || true
  die "the environment in $VENV does not import PETSc and mpi4py, or ssw's chain step (see above)"
}
compile_ssw -j 0
rm -f "$VENV"/.ssw-setup-*
touch "$stamp"
log "environment ready ($VENV, $id_line)"
