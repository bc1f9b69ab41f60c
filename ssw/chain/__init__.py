"""Stage II: dynamics of the bead chain and the time of flight (TOF).

Modules: :mod:`~ssw.chain.params` (the chain), :mod:`~ssw.chain.dissipation` (the contacts'
dissipation laws), :mod:`~ssw.chain.wall` (the last contact's protocol), its laws
:mod:`~ssw.chain.wall_power`, :mod:`~ssw.chain.wall_table` and :mod:`~ssw.chain.wall_base`,
:mod:`~ssw.chain.statics` (gravity precompression), :mod:`~ssw.chain.integrate` (batched
velocity Verlet) and its records :mod:`~ssw.chain.recording`, :mod:`~ssw.chain.tof` (peak
picking), :mod:`~ssw.chain.run` (runs of prebuilt walls, a truncated record refused),
:mod:`~ssw.chain.baseline` (scipy DOP853 reference).

The chain knows only the :class:`~ssw.chain.wall.Wall` protocol and the laws made of its own
numbers; the laws by name are :mod:`ssw.walls`, the TOF on a named wall, its sweeps and its
inverse :mod:`ssw.tof`.
"""
