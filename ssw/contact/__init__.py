"""Stage I: axisymmetric FEM of a rigid sphere indenting a plate on an elastic soil.

gmsh meshes the (r, z) section (:mod:`.mesh`), a Taylor-Hood u-p element (:mod:`.elements`,
:mod:`.assembly`) handles nu up to 0.5, PETSc factors the stiffness once
(:mod:`.petsc_solver`), and the frictionless sphere contact is an LCP on the condensed
candidate dofs at every increment (:mod:`.contact_lcp`). Entry point: :func:`solve_scene`.
"""

from ssw.contact.scene import DEFAULTS, solve_curve, solve_scene, strain_energy

__all__ = ["DEFAULTS", "solve_curve", "solve_scene", "strain_energy"]
