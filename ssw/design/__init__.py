"""Plate design: which plate under the chain makes the device most sensitive to the soil's
modulus while the plate stays elastic and the sample yields least.

:mod:`.spec` states the question (soils, plates, objective, limits); :mod:`.evaluate`
evaluates one plate over the soils (the chain with the exact FEM wall, the contact's
stresses, the mass); :mod:`.optimize` searches the thickness per material, ranks the
candidates and draws the Pareto front; :mod:`.run` runs a whole design and merges the
results of several; :mod:`.output` writes its table and figure.

Device design (the whole device as the design variable): :mod:`.space` the devices searched,
:mod:`.device_spec` the question, :mod:`.device_eval` one device over the soils (resolution
with the DAQ of :mod:`.sampling`, pulses, yield, mass, length), :mod:`.device_search` the
scan, bounded search and ranking, :mod:`.device_output` its table and figure.
"""

from ssw.design.evaluate import Candidate, Evaluator
from ssw.design.optimize import merit, pareto_front, rank, search
from ssw.design.run import DesignResult, merge_results, run_design
from ssw.design.spec import DesignSpec, spec_from_config

__all__ = ["Candidate", "DesignResult", "DesignSpec", "Evaluator", "merge_results", "merit",
           "pareto_front", "rank", "run_design", "search", "spec_from_config"]
