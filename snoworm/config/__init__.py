"""Layer *config*: scenarios as typed, validated, frozen configuration (docs/architecture.md).

:mod:`~snoworm.config.yamlio` (the hardened YAML reader), :mod:`~snoworm.config.schema` (the field
builders and :class:`~snoworm.config.schema.ScenarioError`), :mod:`~snoworm.config.params` (the
parameter sets: the paper's, and the user's files), :mod:`~snoworm.config.sections` (the sections of a scenario file),
:mod:`~snoworm.config.mode_registry` (the mode section's base and the registry of mode types) and
:mod:`~snoworm.config.scenario` (:class:`~snoworm.config.scenario.Scenario`, loading, overrides).
"""
