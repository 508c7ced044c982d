"""Layer *model*: the pieces the chain kernel (:mod:`snoworm.dynamics`) is assembled from.

:mod:`~snoworm.model.arrays` (the chain's parameter arrays and its named state layout),
:mod:`~snoworm.model.inputs` (:class:`~snoworm.model.inputs.Controls`, the piecewise-constant
inputs of one integration interval), :mod:`~snoworm.model.jacobian` (the Jacobian's sparsity and
banded finite differences) and :mod:`~snoworm.model.quantities` (the output quantities computed
from solved states).
"""
