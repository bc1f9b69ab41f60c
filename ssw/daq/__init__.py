"""Stage III acquisition: NI 9234 settings, backends (nidaqmx, simulated), HDF5 recordings.

* :mod:`ssw.daq.settings`: the ``daq:`` config section as a checked frozen dataclass;
* :mod:`ssw.daq.backend`: the backend registry and the session loop;
* :mod:`ssw.daq.nidaq`: real acquisition through NI-DAQmx;
* :mod:`ssw.daq.simulated`: the chain's sensor force through a modelled NI 9234;
* :mod:`ssw.daq.recording`: session files (one dataset per hit, flushed per hit);
* :mod:`ssw.daq.trigger`: the one trigger rule (first crossing, long-channel splitting, the
  ring-buffer software trigger of continuous acquisition);
* :mod:`ssw.daq.importers`: recordings made elsewhere (TDMS, CSV, MAT; :mod:`ssw.daq.formats`).
"""
