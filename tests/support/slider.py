"""A one-mode system: a carriage on a servo-driven rail (the vibration tests' closed form)."""

from __future__ import annotations

from pathlib import Path

import pkdyn

SLIDER = """<?xml version="1.0"?>
<robot name="slider" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="base"/>
  <link name="carriage">
    <inertial>
      <origin xyz="0 0 0"/>
      <mass value="{mass}"/>
      <inertia ixx="0.001" iyy="0.001" izz="0.001" ixy="0" ixz="0" iyz="0"/>
    </inertial>
  </link>
  <joint name="rail" type="prismatic">
    <parent link="base"/>
    <child link="carriage"/>
    <origin xyz="0 0 0.5"/>
    <axis xyz="1 0 0"/>
    <limit lower="-0.5" upper="0.5" effort="{effort}" velocity="10"/>
  </joint>
  <pkdyn:platform link="carriage" xyz="0 0 0" rpy="0 0 0" task="x"/>
  <transmission name="rail_transmission">
    <type>transmission_interface/SimpleTransmission</type>
    <joint name="rail">
      <hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface>
    </joint>
    <actuator name="motor"><mechanicalReduction>1</mechanicalReduction></actuator>
  </transmission>
</robot>
"""


def slider(directory: Path, mass: float = 1.0, effort: float = 1000.0) -> pkdyn.Robot:
    """The slider written to ``directory`` and loaded (carriage ``mass`` [kg], rail along x,
    actuator ``effort`` limit [N])."""
    path = Path(directory) / "slider.urdf"
    path.write_text(SLIDER.format(mass=mass, effort=effort))
    return pkdyn.load(str(path))
