"""Layer *results*: what a run produced, on disk and in memory.

:mod:`~snoworm.results.result` (:class:`~snoworm.results.result.Result`, its folder, ``load_result``),
:mod:`~snoworm.results.energy` (energy metrics and balance), :mod:`~snoworm.results.frames`
(results as pandas tables and xarray datasets), :mod:`~snoworm.results.verdict` (the run's
verdict: moving, reached the end of its route, or immobilised, where, when and why) and
:mod:`~snoworm.results.step` (step-response metrics of a controlled run).
"""
