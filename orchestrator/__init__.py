"""The sonotrack orchestrator: FMU build and validation, SSP systems, the master algorithm,
recording, sweeps, reports and the ``sonotrack`` command line.

Sub-modules are imported lazily by the CLI; import what you need directly, e.g.
``from orchestrator.builder.fmus import build_all``.
"""
