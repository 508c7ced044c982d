"""Layer *studies*: many runs and comparisons, built on the same API a notebook uses.

:mod:`~snoworm.studies.sweep` (parameter sweeps), :mod:`~snoworm.studies.paper` (the paper's
figures and claims), :mod:`~snoworm.studies.mobility` (mobility maps),
:mod:`~snoworm.studies.groundtruth` (field data, Table 2, terrain curves) and
:mod:`~snoworm.studies.calibrate` (fitting terrain coefficients to the field data).
"""
