"""ssw: parametric studies for the solitary strain wave (SSW) device.

Stages (Torres Constante 2024, USFQ thesis; see ``shared/REFERENCE.md``):

* ``ssw.contact``: axisymmetric FEM of a rigid sphere indenting a plate on soil (Stage I);
* ``ssw.fit``: modified-Hertz fits K(E, nu) of those curves;
* ``ssw.chain``: dynamics of the bead chain and time of flight (Stage II);
* ``ssw.daq`` / ``ssw.signal`` / ``ssw.validate``: acquisition, TOF from recordings and
  validation against the thesis's Tables 2 and 3 (Stage III).

All quantities are SI (m, N, Pa, kg, s) unless a name says otherwise.
"""

import importlib.machinery as _machinery
import os as _os
import sys as _sys
import types as _types

# ssw runs in parallel across processes (Snakemake jobs, MPI ranks over scenes and sweep
# points), never inside one: a threaded BLAS only contends for the cores those processes
# use, and on ssw's small dense systems (condensed operators, LCPs, Jacobians) it was
# measured up to 10x slower than one thread on the 2-core machines we run on. Set before
# numpy loads; an explicit setting of the user's wins.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

__version__ = "0.1.0"


# ---- the code this process runs
#: The source of every module of ssw this process loaded, as it loaded it: resolved path ->
#: (its bytes, (mtime in ns, size in bytes) of the file then). Provenance hashes these
#: (:func:`ssw.provenance.source_hash`), not the files on disk when it is called: an edit
#: during a run changes what later processes load, never the label of what ran. A fork
#: (``ssw.warmstart``) inherits its parent's.
LOADED: dict[str, tuple[bytes, tuple[int, int]]] = {}


def _stat_key(path: str) -> tuple[int, int]:
    st = _os.stat(path)
    return st.st_mtime_ns, st.st_size


def _remember(path: str) -> tuple[bytes, tuple[int, int]]:
    """A source file's bytes and the (mtime, size) they go with: read again while the file
    changes under the read (three tries; then the last read, whose stat it may not be)."""
    for _ in range(3):
        before = _stat_key(path)
        with open(path, "rb") as fh:
            data = fh.read()
        if _stat_key(path) == before and len(data) == before[1]:
            break
    return data, before


class _SourceLoader(_machinery.SourceFileLoader):
    """Python's loader of a module's source (its bytecode cache as usual) that keeps the
    bytes the module's code comes from in :data:`LOADED`; when the file changed while it
    loaded, it compiles the bytes it kept (the cache could hold either version)."""

    def get_code(self, fullname: str) -> _types.CodeType:
        path = self.get_filename(fullname)
        data, stat = _remember(path)
        code = super().get_code(fullname)
        if _stat_key(path) != stat:
            code = self.source_to_code(data, path)
        LOADED[_os.path.realpath(path)] = (data, stat)
        return code


class _SourceFinder:
    """Finds ssw's submodules as Python's path finder does, with :class:`_SourceLoader`."""

    @staticmethod
    def find_spec(name: str, path: "list[str] | None" = None,
                  target: _types.ModuleType | None = None) -> _machinery.ModuleSpec | None:
        if path is None or not name.startswith(f"{__name__}."):
            return None
        spec = _machinery.PathFinder.find_spec(name, path, target)
        if spec is not None and type(spec.loader) is _machinery.SourceFileLoader:
            spec.loader = _SourceLoader(spec.loader.name, spec.loader.path)
        return spec


if not any(f is _SourceFinder for f in _sys.meta_path):
    _sys.meta_path.insert(0, _SourceFinder)
    LOADED[_os.path.realpath(__file__)] = _remember(__file__)
