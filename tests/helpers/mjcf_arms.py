"""MJCF descriptions written for the tests of the MuJoCo bridge (test helper; no MuJoCo needed to import it).

``SPATIAL_ARM``: a 3-joint spatial arm whose links exercise every way MJCF gives an inertia — ``fullinertia``,
``diaginertia`` with ``quat``, inertia inferred from geoms — plus a welded hand body, a joint away from its body's
origin, a joint with a ``ref``, and on every joint damping, armature and frictionloss. A floor plane under it.
"""

from __future__ import annotations

#: the arm's joint parameters as written in SPATIAL_ARM: name → (damping, armature, frictionloss)
SPATIAL_JOINTS = {"shoulder": (0.4, 0.02, 0.3), "elbow": (0.3, 0.015, 0.2), "wrist": (0.1, 0.005, 0.05)}

SPATIAL_ARM = """
<mujoco model="spatial3">
  <compiler angle="radian"/>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <geom name="floor" type="plane" size="3 3 0.1"/>
    <body name="base" pos="0 0 0.2">
      <geom type="cylinder" size="0.06 0.05" mass="3"/>
      <body name="upper" pos="0 0 0.1" euler="0 0 0.4">
        <joint name="shoulder" type="hinge" axis="0 0 1" damping="0.4" armature="0.02" frictionloss="0.3"
               range="-2.5 2.5"/>
        <inertial pos="0.01 0.02 0.05" mass="2.0" fullinertia="0.02 0.025 0.015 0.001 -0.002 0.0015"/>
        <body name="fore" pos="0.05 0 0.12" euler="0.3 0 0">
          <joint name="elbow" type="hinge" axis="0 1 0" pos="0 0 0.02" damping="0.3" armature="0.015"
                 frictionloss="0.2" range="-2 2"/>
          <inertial pos="0.2 0.01 0" mass="1.5" diaginertia="0.004 0.03 0.031" quat="0.9 0.1 0.2 0.1"/>
          <body name="distal" pos="0.4 0 0">
            <joint name="wrist" type="hinge" axis="0.2 1 0" ref="0.2" damping="0.1" armature="0.005"
                   frictionloss="0.05"/>
            <geom type="capsule" fromto="0.02 0 0 0.25 0 0" size="0.025" density="900"/>
            <body name="hand" pos="0.28 0 0">
              <geom type="box" size="0.02 0.03 0.015" density="2000"/>
              <geom name="fingertip" type="sphere" pos="0.05 0 0" size="0.02" density="1000"/>
              <site name="tool" pos="0.05 0 0"/>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor joint="shoulder" gear="50" forcelimited="true" forcerange="-1.2 1.2"/>
    <general joint="elbow" gear="2" forcelimited="true" forcerange="-30 25"/>
    <motor joint="wrist" ctrllimited="true" ctrlrange="-8 8"/>
  </actuator>
</mujoco>
"""

#: a slide joint and two hinges in one body (MuJoCo applies them in order), under a body welded to the world
SLIDE_AND_STACKED = """
<mujoco model="slide_stacked">
  <worldbody>
    <body name="rail" pos="0.1 0 0.3" quat="0.96 0 0.28 0">
      <body name="carriage">
        <joint name="slide" type="slide" axis="1 0 0" ref="0.05"/>
        <geom type="box" size="0.1 0.05 0.05" density="500"/>
        <body name="wrist" pos="0.1 0 0.1">
          <joint name="yaw" type="hinge" axis="0 0 1" pos="0 0.02 0"/>
          <joint name="pitch" type="hinge" axis="0 1 0" pos="0.03 0 0"/>
          <geom type="capsule" fromto="0 0 0 0.3 0.05 0" size="0.02"/>
          <site name="tip" pos="0.3 0.05 0"/>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""
