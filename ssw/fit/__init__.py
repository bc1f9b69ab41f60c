"""Modified-Hertz fits of contact curves and their aggregation into K(E, nu).

Modules: :mod:`~ssw.fit.laws` (the law registry), :mod:`~ssw.fit.fitting` (one curve),
:mod:`~ssw.fit.range` (the default fit range), :mod:`~ssw.fit.table` (K(E, nu) tables and
their interpolant), :mod:`~ssw.fit.deviation` (deviation from Hertz, the thesis's Sets 1-2).
"""
