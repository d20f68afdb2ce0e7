"""How people use the kit: the ``ddp-lite`` command line (``cli`` and its ``cli_*`` handlers), the
classroom tools (``classroom``: student copies, solutions, the exercise table; ``grading``: hand-ins
run and scored, ``grading_kernel``: a submission's code in its kernel, the checks in the grader;
``grades``: points by hand, tables, feedback) and the notebooks' exercise checks (``exercises``).

May import every other part of ddp_lite.
"""
