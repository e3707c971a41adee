"""The book's mechanics, one module per idea, each written once over a backend (floats or straight-line programs):

* :mod:`.linalg` 3-vectors and 3x3 blocks with structural zeros skipped; :mod:`.group` the motion group L(R,6)
  (1.9)-(1.23); :mod:`.aggregates` Mises matrices and symmetric 6x6 blocks, their congruences (2.3), (2.7);
* :mod:`.bound` the model bound to a backend; :mod:`.kinematics` pairs, quasi-velocities, S (1.24)-(1.43);
* :mod:`.inertia` A(q) (2.30)-(2.34); :mod:`.bias` b, g, B (2.36)-(2.37); :mod:`.sweeps` inverse dynamics and
  joint wrenches (2.39)-(2.46); :mod:`.transvective` the factors of A^-1 and forward dynamics (3.7)-(3.20);
  :mod:`.elastic` Hooke pairs (2.27), Prop. 2.14; :mod:`.energy` T and U; :mod:`.coupling` coordinates tied
  to others (mimic joints).

Nothing here imports the code generator.
"""
