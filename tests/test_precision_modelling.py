"""The stiffness model's modelling choices, each against an independent model (issue 35, item 4).

The robot: one beam (a steel or carbon rod along x, length L) on a revolute joint held rigidly
(``inf``), its tip the platform, written as a description in the test. Truths written out here:

- the Timoshenko cantilever with shear, ``L^3 / (3 E I) + L / (kappa G A)``, with Cowper's
  coefficient for an isotropic material and the section's alone (``nu = 0``) for carbon, whose
  ``E / (2 G) - 1 = 11`` is no Poisson ratio;
- a spring tying the beam to the ground at its middle: the cantilever with an intermediate
  spring support, by superposition (the spring acting at the tip: 2.8 times too stiff);
- ``mass="from-material"``: the link weighs ``density A L``, its inertia about the joint
  ``m (L^2 / 3 + r^2 / 4)``, and the frequency of the actuator spring on it;
- the materials of a description from the command line, ``--material`` only for the
  undescribed links, ``--shear off``.

The prismatic leg's length across the stroke: ``tests/test_precision_stiffness.py``.
"""

import json

import numpy as np
import pytest

import pkdyn
from pkdyn.cli import main
from pkdyn.precision import CARBON, STEEL, Section, elastic_model, modes, stiffness

L, R, A_TIE, H_TIE = 0.5, 0.012, 0.25, 0.2


def beam_xml(material="steel", spring=None, mass=None, k_a=None, extra=""):
    """One rod along x on a revolute joint about z; platform at its tip (task x y z)."""
    stiff = "" if k_a is None else f'<pkdyn:stiffness value="{k_a}"/>'
    tie = ""
    if spring is not None:
        tie = (
            f'<pkdyn:spring name="tie" stiffness="{spring}" rest_length="{H_TIE}">'
            f'<pkdyn:frame link="base" xyz="{A_TIE} 0 {-H_TIE}"/>'
            f'<pkdyn:frame link="beam" xyz="{A_TIE} 0 0"/></pkdyn:spring>'
        )
    mass_attr = "" if mass is None else f' mass="{mass}"'
    mat = "" if material is None else f'<pkdyn:material name="{material}"{mass_attr}/>'
    return f"""<robot name="beam" xmlns:pkdyn="urn:pkdyn:urdf:1">
  <link name="base"/>
  <link name="beam">
    <inertial><origin xyz="{L / 2} 0 0"/><mass value="2.0"/>
      <inertia ixx="0.001" iyy="0.05" izz="0.05" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="{L / 2} 0 0" rpy="0 1.5707963267948966 0"/>
      <geometry><cylinder radius="{R}" length="{L}"/></geometry></collision>
  </link>
  <joint name="a1" type="revolute"><parent link="base"/><child link="beam"/>
    <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="100" velocity="10"/></joint>
  <transmission name="t1"><type>transmission_interface/SimpleTransmission</type>
    <joint name="a1"/><actuator name="motor">{stiff}<mechanicalReduction>1</mechanicalReduction>
    </actuator></transmission>
  {mat}{tie}{extra}
  <pkdyn:platform link="beam" xyz="{L} 0 0" task="x y z"/>
</robot>"""


def _load(tmp_path, xml, name="beam.urdf"):
    path = tmp_path / name
    path.write_text(xml)
    return pkdyn.load(str(path)), path


def _cowper(m2, nu):
    return 6 * (1 + nu) * (1 + m2) ** 2 / ((7 + 6 * nu) * (1 + m2) ** 2 + (20 + 12 * nu) * m2)


@pytest.mark.parametrize("material", ["steel", "carbon"])
def test_timoshenko_cantilever_with_the_section_shear_coefficient(tmp_path, material):
    robot, _ = _load(tmp_path, beam_xml(material))
    mat = {"steel": STEEL, "carbon": CARBON}[material]
    sec = Section(R)
    E, G, A, I = mat.E, mat.G, sec.area, sec.second_moment
    nu = E / (2 * G) - 1
    kappa = _cowper(0.0, nu if material == "steel" else 0.0)  # carbon: the section alone
    C = stiffness(robot, robot.q_home, np.inf).compliance
    bend = L**3 / (3 * E * I) + L / (kappa * G * A)
    np.testing.assert_allclose(np.diag(C), [L / (E * A), bend, bend], rtol=1e-9)
    euler = stiffness(robot, robot.q_home, np.inf, shear=False).compliance
    np.testing.assert_allclose(euler[1, 1], L**3 / (3 * E * I), rtol=1e-9)
    shear = C[1, 1] - euler[1, 1]
    assert shear == pytest.approx(L / (kappa * G * A), rel=1e-6)
    if material == "carbon":  # E / (2G) - 1 = 11 taken for a Poisson ratio: 13 % off in shear
        wrong = L / (_cowper(0.0, 11.0) * G * A)
        assert abs(wrong / shear - 1.0) > 0.1
        assert CARBON.poisson is None and not CARBON.isotropic and STEEL.isotropic


def test_a_spring_acts_at_its_point_on_the_beam(tmp_path):
    """A tie to the ground at mid-span: the cantilever on an intermediate spring support."""
    k_s = 2e5
    robot, _ = _load(tmp_path, beam_xml("steel", spring=k_s))
    S = stiffness(robot, robot.q_home, np.inf)
    E, G, A, I = STEEL.E, STEEL.G, Section(R).area, Section(R).second_moment
    kappa = _cowper(0.0, STEEL.E / (2 * STEEL.G) - 1)
    a = A_TIE

    def tip_per_F(x):  # transverse deflection at x of a tip force, per N
        return x**2 * (3 * L - x) / (6 * E * I) + x / (kappa * G * A)

    d_aa = a**3 / (3 * E * I) + a / (kappa * G * A)  # at a, per N at a
    # compatibility at a: tip_per_F(a) F - d_aa R = R / k_s; tip: tip_per_F(L) F - tip_per_F(a) R
    R_per_F = tip_per_F(a) / (d_aa + 1.0 / k_s)
    c_zz = tip_per_F(L) - tip_per_F(a) * R_per_F
    assert S.compliance[2, 2] == pytest.approx(c_zz, rel=1e-7)
    # the spring acting at the tip instead (the old model): 2.8 times too stiff here
    at_tip = tip_per_F(L) - tip_per_F(L) ** 2 / (tip_per_F(L) + 1.0 / k_s)
    assert abs(at_tip / c_zz - 1.0) > 0.03
    # the other directions: the spring is vertical, the beam alone
    np.testing.assert_allclose(S.compliance[1, 1], tip_per_F(L), rtol=1e-9)


def test_mass_from_material(tmp_path):
    own = '<pkdyn:compliance link="beam" material="steel" mass="from-material"/>'
    xml = beam_xml(None, extra=own)
    robot, _ = _load(tmp_path, xml)
    em = elastic_model(robot, 3e3)
    m = STEEL.density * np.pi * R**2 * L
    inertia = em.base.model.inertias[1]
    assert inertia.mass == pytest.approx(m, rel=1e-12)
    # described (URDF) mass otherwise
    plain, _ = _load(tmp_path, beam_xml("steel"), "plain.urdf")
    assert elastic_model(plain, 3e3).base.model.inertias[1].mass == pytest.approx(2.0)
    # the actuator spring on the beam's own inertia about the joint: f = sqrt(k / I) / 2 pi
    xml = beam_xml(None, extra=(
        '<pkdyn:compliance link="beam" material="stiff" E="1e17" G="4e16" density="7850" '
        'mass="from-material"/>'
    ))  # fmt: skip
    rigidish, _ = _load(tmp_path, xml, "rigid.urdf")
    I_axis = m * (L**2 / 3 + R**2 / 4)
    f = modes(rigidish, rigidish.q_home, 3e3).f1
    assert f == pytest.approx(np.sqrt(3e3 / I_axis) / (2 * np.pi), rel=1e-6)


def test_description_materials_from_the_command_line(tmp_path, capsys):
    robot, path = _load(tmp_path, beam_xml("steel", k_a=5e3))
    argv = ["stiffness", str(path), "--qa", "0.1", "--json"]
    assert main(argv) == 0  # no --material: the description's own
    out = json.loads(capsys.readouterr().out)
    q = pkdyn.forward_geometry(robot, [0.1]).q
    S = stiffness(robot, q)
    np.testing.assert_allclose(out["compliance"], S.compliance, rtol=1e-12)
    assert out["links"] == ["beam"]
    assert main([*argv, "--shear", "off"]) == 0
    off = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(off["compliance"], stiffness(robot, q, shear=False).compliance)
    assert off["compliance"][1][1] < out["compliance"][1][1]
    # --material for the undescribed links only, and a note naming them (none here)
    assert main(["stiffness", str(path), "--qa", "0.1", "--material", "aluminium"]) == 0
    captured = capsys.readouterr()
    assert "not used" in captured.err and captured.err.count("\n") == 1
    # a description that leaves the link undescribed: --material applies to it, named
    _, bare = _load(tmp_path, beam_xml(None, k_a=5e3), "bare.urdf")
    assert main(["stiffness", str(bare), "--qa", "0.1", "--material", "aluminium"]) == 0
    err = capsys.readouterr().err
    assert "applies to the links the description leaves undescribed: beam" in err


def test_a_material_without_cylinders_says_what_is_missing(capsys):
    argv = ["modes", "five_bar", "--qa", "1.2", "1.9", "--actuator-stiffness", "1e3"]
    robot = pkdyn.load("five_bar", geometry=False)
    from pkdyn.exceptions import InvalidInputError

    with pytest.raises(InvalidInputError, match="has no collision or visual geometry"):
        elastic_model(robot, 1e3, "steel")
    assert main([*argv, "--material", "steel"]) == 0  # the library five-bar has cylinders
    capsys.readouterr()
