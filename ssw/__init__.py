"""ssw: parametric studies for the solitary strain wave (SSW) device.

Stages (Torres Constante 2024, USFQ thesis; see ``shared/REFERENCE.md``):

* ``ssw.contact``: axisymmetric FEM of a rigid sphere indenting a plate on soil (Stage I);
* ``ssw.fit``: modified-Hertz fits K(E, nu) of those curves;
* ``ssw.chain``: dynamics of the bead chain and time of flight (Stage II);
* ``ssw.daq`` / ``ssw.signal`` / ``ssw.validate``: acquisition, TOF from recordings and
  validation against the thesis's Tables 2 and 3 (Stage III).

All quantities are SI (m, N, Pa, kg, s) unless a name says otherwise.
"""

__version__ = "0.1.0"
