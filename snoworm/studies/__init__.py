"""Layer *studies*: many runs and comparisons, built on the same API a notebook uses.

:mod:`~snoworm.studies.sweep` (parameter sweeps), :mod:`~snoworm.studies.paper` (the paper's
figures and claims), :mod:`~snoworm.studies.mobility` (mobility maps
and their inching runs; the gradeability per gait in :mod:`~snoworm.studies.gradeability`),
:mod:`~snoworm.studies.groundtruth` (Table 2, terrain curves), :mod:`~snoworm.studies.field_data`
(reading field data) and
:mod:`~snoworm.studies.calibrate` (fitting terrain coefficients to the field data).
"""
