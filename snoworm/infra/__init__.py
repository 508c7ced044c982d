"""Layer *infra*: small infrastructure any layer may use; imports nothing of snoworm but the version.

:mod:`~snoworm.infra.folders` (atomic files, all-or-nothing output folders synced to disk, manifests),
:mod:`~snoworm.infra.commit` (a folder committed entry by entry, recoverably),
:mod:`~snoworm.infra.locks` (one process at a time writes a folder; the output errors),
:mod:`~snoworm.infra.csvwriter` (the one CSV writer of result tables), :mod:`~snoworm.infra.pool`
(the local process pool of studies), :mod:`~snoworm.infra.progress` (progress bars and logs),
:mod:`~snoworm.infra.manifest` (manifests read defensively) and :mod:`~snoworm.infra.files` (a user's small file read without hanging on a FIFO).
"""
