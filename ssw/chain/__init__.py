"""Stage II: dynamics of the bead chain and the time of flight (TOF).

Modules: :mod:`~ssw.chain.params` (the chain), :mod:`~ssw.chain.wall` (last-contact laws),
:mod:`~ssw.chain.statics` (gravity precompression), :mod:`~ssw.chain.integrate` (batched
velocity Verlet), :mod:`~ssw.chain.tof` (peak picking), :mod:`~ssw.chain.api` (public
entry points), :mod:`~ssw.chain.sweep`, :mod:`~ssw.chain.inverse`,
:mod:`~ssw.chain.baseline` (scipy DOP853 reference).
"""
