"""ssw: parametric studies for the solitary strain wave (SSW) device.

Stages (Torres Constante 2024, USFQ thesis; see ``shared/REFERENCE.md``):

* ``ssw.contact``: axisymmetric FEM of a rigid sphere indenting a plate on soil (Stage I);
* ``ssw.fit``: modified-Hertz fits K(E, nu) of those curves;
* ``ssw.chain``: dynamics of the bead chain and time of flight (Stage II);
* ``ssw.daq`` / ``ssw.signal`` / ``ssw.validate``: acquisition, TOF from recordings and
  validation against the thesis's Tables 2 and 3 (Stage III).

All quantities are SI (m, N, Pa, kg, s) unless a name says otherwise.
"""

import os as _os

# ssw runs in parallel across processes (Snakemake jobs, MPI ranks over scenes and sweep
# points), never inside one: a threaded BLAS only contends for the cores those processes
# use, and on ssw's small dense systems (condensed operators, LCPs, Jacobians) it was
# measured up to 10x slower than one thread on the 2-core machines we run on. Set before
# numpy loads; an explicit setting of the user's wins.
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    _os.environ.setdefault(_var, "1")

__version__ = "0.1.0"
