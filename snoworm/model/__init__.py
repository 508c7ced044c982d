"""Layer *model*: the chain kernel in one place (its public face is :mod:`snoworm.dynamics`).

:mod:`~snoworm.model.chain` (:class:`~snoworm.model.chain.ChainModel`: the laws composed into
one right-hand side, its inputs, outputs and Jacobian), :mod:`~snoworm.model.floatkernel` and
:mod:`~snoworm.model.symbolic` (the float code of a short chain, traced from the kernel),
:mod:`~snoworm.model.arrays` (the chain's parameter arrays and its named state layout),
:mod:`~snoworm.model.inputs` (:class:`~snoworm.model.inputs.Controls`, the piecewise-constant
inputs of one integration interval), :mod:`~snoworm.model.jacobian` (the Jacobian's sparsity and
banded finite differences) and :mod:`~snoworm.model.quantities` (the output quantities computed
from solved states).
"""
