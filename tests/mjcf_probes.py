"""Single-feature MJCF files for the joint ``ref`` (issue 49): each one feature of a real file, compared with MuJoCo in
tests/test_mjcf_ref.py and pose by pose in tests/test_mjcf_poses.py.

MuJoCo: a hinge's or slide's ``ref`` is the joint's value in the file's configuration (qpos0 = ref), the joint
turns (slides) its body by qpos - qpos0; aggsym's q is qpos.  Masses span six decades, angles are written with 5
digits, axes are not unit vectors (MuJoCo normalises them).
"""

# the issue's probe: a hinge with ref="30" (compiler angle="degree", MuJoCo's default) below another hinge
ISSUE = """<mujoco model="refprobe"><worldbody>
<body name="b1" pos="0 0 1"><joint name="j1" type="hinge" axis="0 1 0"/>
 <geom type="capsule" fromto="0 0 0 0 0 -.5" size=".05"/>
 <body name="b2" pos="0 0 -.5"><joint name="j2" type="hinge" axis="1 0 0" ref="30"/>
  <geom type="capsule" fromto="0 0 0 .1 0 -.5" size=".05"/></body></body>
</worldbody></mujoco>"""

# a chain of three hinges, each placed by {euler} and turning about {axis} with the reference angles {refs}
HINGES = """<mujoco model="hinges"><compiler angle="degree"/><option gravity="0.31 -0.2 -9.81"/><worldbody>
<body name="a" pos="0.1 -0.2 0.3" euler="{euler}"><joint name="j1" axis="{axis}" ref="{r1}"/>
 <geom type="capsule" fromto="0 0 0 .3 .1 -.2" size=".04" mass="2.1"/>
 <body name="b" pos=".3 .1 -.2" euler="{euler}"><joint name="j2" axis="{axis2}" ref="{r2}"/>
  <geom type="box" size=".1 .04 .02" pos=".1 0 -.05" euler="11.123 0 -7.5" mass="0.00137"/>
  <body name="c" pos=".2 -.05 .1"><joint name="j3" axis="{axis}" ref="{r3}"/>
   <geom type="ellipsoid" size=".05 .03 .02" pos="0 .04 -.1" mass="1370"/></body></body></body>
</worldbody></mujoco>"""

HINGE_CASES = {  # euler, axis of j1 and j3, axis of j2, refs
    "x": ("0 0 0", "1 0 0", "0 1 0", ("30", "-47.123", "0")),
    "minus-y": ("0 0 0", "0 -1 0", "0 0 1", ("-12.5", "90", "179.99")),
    "oblique": ("17.123 -43.21 88.001", "0.3 -0.7 0.2", "-0.51 0.1 0.84", ("33.333", "-71.002", "5.4321")),
    "turned-z": ("0 0 90", "0 0 -1", "1 1 0", ("-90", "45", "-123.45")),
}

# slides with a ref after a hinge and before one (a slide under the world only shifts a constant mass: here it
# carries a hinge, and a hinge carries the other)
SLIDES = """<mujoco model="slides"><compiler angle="radian"/><option gravity="0 0.4 -9.81"/><worldbody>
<body name="s" pos="0 0 .5" euler="0.1 0.2 0.3"><joint name="root" type="slide" axis="0.2 -0.5 1" ref="0.37215"/>
 <geom type="box" size=".1 .1 .1" mass="3.2"/>
 <body name="h" pos=".1 0 0"><joint name="hinge" axis="0 1 0.3" ref="0.71234"/>
  <geom type="capsule" fromto="0 0 0 .4 0 .1" size=".03" mass="0.5"/>
  <body name="t" pos=".4 0 .1"><joint name="tip" type="slide" axis="1 -0.4 0.25" ref="-0.12345"/>
   <geom type="sphere" size=".05" pos="0 .1 0" mass="0.0042"/></body></body></body>
</worldbody></mujoco>"""

# refs with springs: a hinge whose spring rest (springref) is not its ref, a slide likewise, a fixed tendon's spring
SPRINGS = """<mujoco model="springs"><compiler angle="radian"/><worldbody>
<body name="a"><joint name="j1" axis="0 1 0" ref="0.52341" stiffness="3.5" springref="-0.2" damping="0.3"/>
 <geom type="capsule" fromto="0 0 0 .3 0 -.2" size=".04"/>
 <body name="b" pos=".3 0 -.2"><joint name="j2" type="slide" axis="1 0 0.5" ref="0.05432" stiffness="40"
  springref="0.1"/><geom type="box" size=".05 .05 .05" mass="0.7"/>
  <body name="c" pos=".1 .05 0"><joint name="j3" axis="1 0 0" ref="-1.2345" armature="0.01"/>
   <geom type="capsule" fromto="0 0 0 0 .2 -.2" size=".02"/></body></body></body>
</worldbody>
<tendon><fixed name="t" stiffness="7" springlength="0.1" damping="0.2"><joint joint="j1" coef="1"/>
 <joint joint="j3" coef="-0.5"/></fixed></tendon></mujoco>"""

# refs with equalities: a linear joint equality (a coupling), and a nonlinear one (a joint-space row); MuJoCo measures
# both from qpos0 = ref
COUPLED = """<mujoco model="coupledref"><compiler angle="radian"/><worldbody>
<body name="a"><joint name="j1" axis="0 1 0" ref="0.41235"/><geom type="capsule" fromto="0 0 0 .3 0 0" size=".03"/>
 <body name="b" pos=".3 0 0"><joint name="j2" axis="0 1 0" ref="-0.8765"/>
  <geom type="capsule" fromto="0 0 0 .3 0 .1" size=".03"/>
  <body name="c" pos=".3 0 .1"><joint name="j3" axis="1 0 0" ref="1.1111"/><geom size=".05"/></body></body></body>
</worldbody><equality><joint name="tie" joint1="j2" joint2="j1" polycoef="0.1 -1.5 0 0 0"/></equality></mujoco>"""

NONLINEAR = COUPLED.replace('polycoef="0.1 -1.5 0 0 0"', 'polycoef="0.1 -1.5 0.3 0 -0.02"')

# joints anchored off the body origin (pos) with a ref, two in one body
ANCHORED = """<mujoco model="anchored"><worldbody>
<body name="a" pos="0 0 1" euler="5 -10 15"><joint name="j1" axis="0 0 1" pos="0.05 -0.02 0.1" ref="25.5"/>
 <geom type="capsule" fromto="0 0 0 .4 0 0" size=".04"/>
 <body name="b" pos=".4 0 0"><joint name="j2" axis="0 1 0" pos="-0.1 0.03 0" ref="-60.25"/>
  <joint name="j3" type="slide" axis="1 0 0" pos="0.02 0 0.01" ref="0.0777"/>
  <geom type="box" size=".15 .03 .02" pos=".15 0 0"/></body></body>
</worldbody></mujoco>"""

# a free body and a ball beside hinges with refs (the refs of the hinges below them)
FREE_AND_BALL = """<mujoco model="freeball"><worldbody>
<body name="f" pos=".2 .1 1" quat="0.9 0.1 -0.2 0.3"><freejoint name="fly"/><geom type="box" size=".2 .1 .05"/>
 <body name="g" pos=".2 0 0"><joint name="k1" axis="1 0.2 0" ref="-33.3"/>
  <geom type="capsule" fromto="0 0 0 0 0 -.3" size=".03"/>
  <body name="s" pos="0 0 -.3"><joint name="ball" type="ball" pos="0 0.01 0"/>
   <geom type="box" size=".05 .02 .1" pos="0 0 -.1"/></body></body></body>
<body name="arm" pos="1 0 0"><joint name="k2" axis="0 0 1" ref="120"/><geom type="capsule" fromto="0 0 0 .3 0 0" size=".03"/>
 <body name="fore" pos=".3 0 0"><joint name="k3" axis="0 1 0" ref="-15" range="-40 70.5"/><geom size=".05" pos=".1 0 0"/></body></body>
</worldbody></mujoco>"""


def hinges(case: str) -> str:
    euler, axis, axis2, (r1, r2, r3) = HINGE_CASES[case]
    return HINGES.format(euler=euler, axis=axis, axis2=axis2, r1=r1, r2=r2, r3=r3)


# the issue's probe in radians: the same model, ref written as pi/6 to 17 digits
ISSUE_RADIAN = ISSUE.replace('<mujoco model="refprobe">', '<mujoco model="refprobe"><compiler angle="radian"/>').replace(
    'ref="30"', 'ref="0.52359877559829882"')


PROBES = {"issue": ISSUE, "issue-radian": ISSUE_RADIAN, **{f"hinges-{c}": hinges(c) for c in HINGE_CASES}, "slides": SLIDES, "springs": SPRINGS,
          "coupled": COUPLED, "nonlinear-equality": NONLINEAR, "anchored": ANCHORED, "free-and-ball": FREE_AND_BALL}
