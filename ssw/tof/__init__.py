"""The device's time of flight on a sample: the chain (:mod:`ssw.chain`) run against a
last-contact law named in :data:`ssw.walls.WALLS`, above both.

Modules: :mod:`~ssw.tof.api` (TOF, peaks, sensor signal and contact forces of broadcast
soils; the public entry points), :mod:`~ssw.tof.sweep` (TOF(E, nu) sweeps, thesis Fig 8),
:mod:`~ssw.tof.inverse` (E from a measured TOF), :mod:`~ssw.tof.impact` (what each fitted
law's error costs in TOF against the exact FEM law).
"""
