"""The model: plate modal data, the scaling to the nondimensional oscillator, its exact
simulator and its analysis.

Subpackages, upstream first: :mod:`~rattle_lab.model.plate` (modal data),
:mod:`~rattle_lab.model.scaling` and :mod:`~rattle_lab.model.linear` (plate, gap and
excitation to the SDF oscillator), :mod:`~rattle_lab.model.sdf` (the exact simulator),
:mod:`~rattle_lab.model.analysis` (orbits, sweeps, maps) and :mod:`~rattle_lab.model.modal`
(the multi-mode impact model).
"""

__all__: list[str] = []
