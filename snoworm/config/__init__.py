"""Layer *config*: scenarios as typed, validated, frozen configuration (docs/architecture.md).

:mod:`~snoworm.config.yamlio` (the hardened YAML reader), :mod:`~snoworm.config.schema` (the field
builders and :class:`~snoworm.config.schema.ScenarioError`), :mod:`~snoworm.config.params` (the
paper's parameter sets), :mod:`~snoworm.config.sections` (the sections of a scenario file) and
:mod:`~snoworm.config.scenario` (:class:`~snoworm.config.scenario.Scenario`, loading, overrides).
"""
