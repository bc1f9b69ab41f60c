"""Beyond quasi-static contact: the soil's inertia and radiation damping at the last contact.

Modules (one concept each):

* :mod:`~ssw.dynamics.system`: the axisymmetric elastodynamic operators of plate and soil
  (stiffness of :mod:`ssw.contact.assembly`, consistent mass, absorbing boundary);
* :mod:`~ssw.dynamics.lu`: one PETSc LU factorization, many solves;
* :mod:`~ssw.dynamics.newmark`: the trapezoidal (average-acceleration) Newmark step with
  the contact forces condensed onto their candidate dofs;
* :mod:`~ssw.dynamics.bead`: the bead's own elastic compliance on the contact candidates;
* :mod:`~ssw.dynamics.domain`: domain size and element size from the wave speeds;
* :mod:`~ssw.dynamics.scales`: step, window and spectrum of a scene from a quasi-static run;
* :mod:`~ssw.dynamics.fem_wall`: the dynamic FEM wall (a wall with internal state, run by
  the chain's one integrator, :func:`ssw.chain.integrate.simulate`; its contact LCP per
  step is :func:`ssw.contact.contact_lcp.solve_lcp`);
* :mod:`~ssw.dynamics.quasistatic`: the quasi-static references (static FEMs in fixed boxes);
* :mod:`~ssw.dynamics.punch`: vertical dynamic stiffness of a rigid punch and its published
  references;
* :mod:`~ssw.dynamics.reduced`: the reduced dynamic wall for sweeps and inversion;
* :mod:`~ssw.dynamics.registry`: wall dynamics by name (``quasi-static``, ``reduced``);
* :mod:`~ssw.dynamics.api`: TOFs of a scene with the FEM or the reduced wall and with
  their quasi-static laws;
* :mod:`~ssw.dynamics.study`: the TOF error of the quasi-static assumption.

SI units throughout.
"""
