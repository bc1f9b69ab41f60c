#!/usr/bin/env bash
# Set up ssw's environment in .venv: system packages (as root), pinned Python packages,
# and PETSc + petsc4py + mpi4py built against one MPI (Debian's MPICH).
#
# Idempotent: a stamp records the hash of this script, constraints.txt and pyproject.toml;
# when nothing changed and the imports still work, it returns in a few seconds.
#
# Why the PETSc recipe looks the way it does (measured on this kind of machine):
#   * PETSc's pip build uses the `mpicc` on PATH and keeps that MPI's RUNPATH in the wheel
#     that pip caches, so MPICH's development package must be installed before it;
#   * petsc4py's isolated build would reuse whatever petsc wheel is cached, so it is built
#     with --no-build-isolation against the petsc just installed in the venv;
#   * the mpi4py binary wheel looks for libmpi.so.12, which Debian's MPICH names
#     libmpich.so.12, so mpi4py is built from source against the same mpicc.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
cd "$here"
VENV=${SSW_VENV:-$here/.venv}
PY=${PYTHON:-python3.11}
command -v "$PY" >/dev/null 2>&1 || PY=python3

log() { printf '[setup] %s\n' "$*" >&2; }

# ---------------------------------------------------------------- system packages
# libopenblas-dev: BLAS/LAPACK for PETSc; libmpich-dev + mpich: the one MPI (mpicc, mpiexec);
# libglu1-mesa, libxrender1, libxcursor1, libxft2, libxinerama1: shared libraries the
# gmsh wheel's libgmsh.so links against even when no window is opened.
# chromium + chromium-driver: the headless browser the report test opens the study report in
# (tests/test_report_browser.py, through selenium; no browser download).
SYS_PKGS=(libopenblas-dev libmpich-dev mpich libglu1-mesa libxrender1 libxcursor1 libxft2
          libxinerama1 libgl1 chromium chromium-driver)
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
MPICC=$(command -v mpicc || true)
if [ -z "$MPICC" ] || ! "$MPICC" -show 2>/dev/null | grep -q mpich; then
  echo "ssw setup: 'mpicc' on PATH must be MPICH's (found: ${MPICC:-none})." >&2
  echo "PETSc, petsc4py and mpi4py must share one MPI; put /usr/bin first on PATH." >&2
  exit 1
fi

# ---------------------------------------------------------------- virtual environment
stamp_src=$(cat scripts/setup.sh constraints.txt pyproject.toml | sha256sum | cut -c1-16)
stamp="$VENV/.ssw-setup-$stamp_src"
if [ -f "$stamp" ] && "$VENV/bin/python" -c \
   "import petsc4py, mpi4py, gmsh, h5py, snakemake, ssw; petsc4py.init(); from petsc4py import PETSc" \
   >/dev/null 2>&1; then
  log "environment up to date ($VENV)"
  exit 0
fi

[ -x "$VENV/bin/python" ] || { log "creating $VENV"; "$PY" -m venv "$VENV"; }
pip() { "$VENV/bin/python" -m pip --disable-pip-version-check -q "$@"; }
C=(-c "$here/constraints.txt")

pip install "${C[@]}" --upgrade pip >/dev/null 2>&1 || true
pip install "${C[@]}" numpy cython setuptools wheel

if ! "$VENV/bin/python" -c "import petsc" >/dev/null 2>&1; then
  log "building PETSc (about 11-15 minutes on 2 cores, once; pip caches the wheel)"
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
pip install "${C[@]}" -e ".[dev]"

"$VENV/bin/python" - <<'PY'
import petsc4py
petsc4py.init()
from petsc4py import PETSc
from mpi4py import MPI
import gmsh, h5py, snakemake  # noqa: F401
assert PETSc.COMM_WORLD.getSize() == MPI.COMM_WORLD.Get_size()
PY
rm -f "$VENV"/.ssw-setup-*
touch "$stamp"
log "environment ready ($VENV)"
