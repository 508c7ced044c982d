"""Layer *simulation*: integrating a scenario's chain in time.

:mod:`~snoworm.simulation.driver` (:func:`~snoworm.simulation.driver.simulate`: the interval
driver for single and batched runs), :mod:`~snoworm.simulation.guard` (work and wall-time limits,
solver breakdowns, sane states), :mod:`~snoworm.simulation.vode` (ODEPACK's VODE stepped one
step at a time) and :mod:`~snoworm.simulation.stepwise` (:class:`~snoworm.simulation.stepwise.Simulator`:
step by step with commands held for ``dt``).
"""
