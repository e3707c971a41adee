"""What the benchmark's sections share, written once: where results and builds go (:mod:`.paths`), measuring a
child process (:mod:`.measure`), ``aggsym generate`` in one and the generated modules (:mod:`.generate`), the host
(:mod:`.environment`), the example-robot-data robots (:mod:`.robots`), the 3-D chains (:mod:`.chain`), tables and
plots (:mod:`.tables`, :mod:`.plots`), the command lines of the sections (:mod:`.cli`), and compiling and running
the C and C++ timing harnesses against the ``pin`` wheel (:mod:`.build`), whose sources sit in this folder
(``bench.h``, ``pinocchio_common.hpp``, ``pinocchio_bench.cpp``, ``contact_bench.h``,
``constrained_derivatives_bench.cpp``, ``generated_only.c``, ``trig_bench.c``).  Nothing here imports a section.
"""
