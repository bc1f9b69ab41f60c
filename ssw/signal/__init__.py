"""TOF from recorded waveforms: conditioning (:mod:`.filters`), incident/reflected peak
picking with sub-sample interpolation (:mod:`.peaks`), per-hit TOF and the hit rejection
rule with mean, standard deviation and COV (:mod:`.tof`)."""
