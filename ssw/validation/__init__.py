"""Stage III validation (thesis Tables 2 and 3, Figs 9 and 10): :mod:`.table` computes the
rows, :mod:`.figures` draws the figures, :mod:`.output` writes CSV/HDF5."""
