"""The generated code's runtime, one state per call, against its peers: the C against Pinocchio C++ (section 3,
:mod:`.pinocchio_cpp`, with solo12's constrained forward dynamics, :mod:`.constrained`), against a CasADi peer
compiled alike (:mod:`.casadi_peer`), the derivatives of constrained dynamics and of impacts against Pinocchio C++
(:mod:`.constrained_derivatives`), the generated Python against Pinocchio's Python call (:mod:`.python_call`), the
sliced routines against one function each (:mod:`.slicing`) and the sincos helper against libm (:mod:`.trig`).
"""
