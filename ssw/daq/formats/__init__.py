"""Recording file formats other than ssw's HDF5 sessions, one module each.

Each module defines ``read(path, **options) -> Recording`` and
``write(path, recording, **options) -> Path``; :mod:`ssw.daq.importers` registers them by
suffix (``.csv``: :mod:`.csvfile`, ``.mat``: :mod:`.matfile`, ``.tdms``: :mod:`.tdmsfile`).
Units and the shared checks live in :mod:`.common`.
"""
