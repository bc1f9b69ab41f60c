"""Modified-Hertz fits of contact curves and their aggregation into K(E, nu).

Modules: :mod:`~ssw.fit.laws` (the law registry: k_hertz, power, two_term),
:mod:`~ssw.fit.fitting` (one curve, one law; which E* is used), :mod:`~ssw.fit.range` (the
default fit range: what the chain reaches), :mod:`~ssw.fit.interp` (PCHIP in log E, linear
in nu, leave-one-out error), :mod:`~ssw.fit.table` (K(E, nu) tables, HDF5/CSV),
:mod:`~ssw.fit.pipeline` (fits as the config asks), :mod:`~ssw.fit.deviation` (deviation
from Hertz; the thesis's Sets 1-2), :mod:`~ssw.fit.figures` (Figs 5-7 analogues). What a
fit's error costs in TOF needs the chain on the fitted walls: :mod:`ssw.tof.impact`.
"""
