"""Whole sequences: one completion per view, resumable (``sequence``, ``sequence_jobs``,
``sequence_files``), its cost (``sequence_cost``), the working size (``working_size``) and the
job runner (``runner``).

May import: core, world, method, data, evaluation.
"""
