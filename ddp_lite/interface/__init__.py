"""How people use the kit: the ``ddp-lite`` command line (``cli``, and one handler file per command
group: ``cli_complete``, ``cli_sequence``, ``cli_demo``, ``cli_classroom``), the classroom tools
(``classroom``: student copies, solutions, the exercise table; ``source_rules``: what a source notebook
must be for a copy that cannot leak an answer; ``grading``: hand-ins run and scored,
``grading_kernel``: a submission's code in its kernel, the checks in the grader; ``grades``: points by
hand, tables, feedback), the notebooks' exercise checks (``exercises``) and their one rule about
whose work an answer is (``own_work``).

May import every other part of ddp_lite.
"""
