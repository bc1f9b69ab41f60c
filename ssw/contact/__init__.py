"""Stage I: axisymmetric FEM of a rigid sphere indenting a plate on an elastic soil.

gmsh meshes the (r, z) section (:mod:`.mesh`), a Taylor-Hood u-p element (:mod:`.elements`,
:mod:`.assembly`) handles nu up to 0.5. The plate and the soil are condensed separately at
unit E onto the dofs they share (:mod:`.substructure`), once per mesh and Poisson's ratio,
and cached (:mod:`.operators`); a scene is then a dense system of a few hundred unknowns
whose frictionless contact LCP is followed exactly along the indentation
(:mod:`.parametric`). The monolithic engine (one PETSc LU of the whole model,
:mod:`.petsc_solver`, :mod:`.condense`, an LCP per increment, :mod:`.contact_lcp`) is the
independent check. Entry points: :func:`solve_scene`, :func:`solve_curve`.
"""

from ssw.contact.scene import DEFAULTS, solve_curve, solve_scene, strain_energy

__all__ = ["DEFAULTS", "solve_curve", "solve_scene", "strain_energy"]
