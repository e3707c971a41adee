"""The MJCF reader against MuJoCo itself: A, b + g - passive and the forward dynamics (:mod:`.mujoco_reference`) and
the poses (:mod:`.mujoco_poses`) of aggsym's models against MuJoCo's, on every model of dm_control's suite and of
gymnasium's MuJoCo environments (:mod:`.corpus`, ``python -m benchmarks.mjcf.corpus``).  The references are the
tests' too.
"""
