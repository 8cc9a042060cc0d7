"""Motor and gearbox catalogs: schema, units, the shipped example, malformed catalogs."""

import math
import textwrap

import numpy as np
import pytest

from pkdyn.dynamics.motors import (
    GEARBOX_FIELDS,
    MOTOR_FIELDS,
    Motor,
    example_catalog,
    load_catalog,
)
from pkdyn.exceptions import CatalogError

RPM = 2 * math.pi / 60

GOOD_MOTOR = {
    "name": "M1",
    "rated_torque": 1.3,
    "peak_torque": 3.8,
    "rated_speed": "3000 rpm",
    "max_speed": "6000 rpm",
    "rotor_inertia": "0.4 kg cm^2",
    "mass": 1.5,
}


def _yaml(tmp_path, motors=(), gearboxes=(), extra=""):
    import yaml

    path = tmp_path / "cat.yaml"
    body = {}
    if motors:
        body["motors"] = list(motors)
    if gearboxes:
        body["gearboxes"] = list(gearboxes)
    path.write_text(yaml.safe_dump(body) + extra)
    return path


def test_example_catalog_is_shipped_and_labelled():
    cat = example_catalog()
    assert len(cat.motors) == 7 and len(cat.gearboxes) == 18 and cat.source == "example"
    assert load_catalog("example") == cat
    m = next(m for m in cat.motors if m.name == "EX-S400")
    assert m.rated_speed == pytest.approx(3000 * RPM) and m.rotor_inertia == pytest.approx(4e-5)
    g = next(g for g in cat.gearboxes if g.name == "EX-P060-20")
    assert g.efficiency == 0.94 and g.max_input_speed == pytest.approx(6000 * RPM)
    from importlib import resources

    text = (resources.files("pkdyn.dynamics") / "catalogs" / "example.yaml").read_text()
    assert "EXAMPLE DATA" in text and "no vendor's data" in text


def test_yaml_and_csv_give_the_same_entries(tmp_path):
    y = load_catalog(_yaml(tmp_path, [GOOD_MOTOR]))
    csv_path = tmp_path / "motors.csv"
    csv_path.write_text(
        "# a comment line\n"
        "name,rated_torque [N m],peak_torque,rated_speed [rpm],max_speed [rpm],"
        "rotor_inertia [kg cm^2],mass [g],price\n"
        "M1,1.3,3.8,3000,6000,0.4,1500,\n"
    )
    c = load_catalog(csv_path)
    assert c.motors[0] == y.motors[0]
    gears = tmp_path / "gears.csv"
    gears.write_text(
        "name,ratio,efficiency,rated_torque,peak_torque,max_input_speed [rpm],inertia\n"
        "G1,10,97 %,20,40,6000,1e-5\n"
    )
    g = load_catalog(gears).gearboxes[0]
    assert (g.ratio, g.efficiency, g.inertia) == (10.0, 0.97, 1e-5)
    both = load_catalog(csv_path) + load_catalog(gears)
    assert len(both.motors) == 1 and len(both.gearboxes) == 1 and "+" in both.source


def test_the_schema_is_documented_in_the_guide():
    from pathlib import Path

    page = Path(__file__).resolve().parents[1] / "docs" / "guide" / "drives.md"
    readme = page.read_text(encoding="utf-8")
    for f in MOTOR_FIELDS + GEARBOX_FIELDS:
        assert f"`{f.name}`" in readme, f.name


def test_motor_envelope():
    m = Motor("M", 1.0, 3.0, 300.0, 600.0, 1e-5, 1.0)
    w = np.array([0.0, 300.0, 450.0, 600.0, 700.0])
    assert np.allclose(m.peak_torque_at(w), [3.0, 3.0, 2.0, 1.0, 0.0])
    assert np.allclose(m.continuous_torque_at(w), [1.0, 1.0, 0.5, 0.0, 0.0])
    assert np.allclose(m.peak_torque_at(-w), m.peak_torque_at(w))


def _bad(**changes):
    m = dict(GOOD_MOTOR)
    for k, v in changes.items():
        if v is None:
            m.pop(k)
        else:
            m[k] = v
    return m


@pytest.mark.parametrize(
    ("motor", "field", "needle"),
    [
        (_bad(peak_torque=None), "peak_torque", "missing"),
        (_bad(rated_torque=-1.0), "rated_torque", "must be > 0"),
        (_bad(rotor_inertia=0), "rotor_inertia", "must be > 0"),
        (_bad(mass=float("nan")), "mass", "finite"),
        (_bad(mass="heavy"), "mass", "expected a number"),
        (_bad(rated_torque="1.3 ft lb"), "rated_torque", "unknown unit 'ft lb'"),
        (_bad(rotor_inertia=0.4), "rotor_inertia", "'0.4 kg cm^2'"),  # kg cm^2 meant
        (_bad(rotor_inertia=400), "rotor_inertia", "outside any plausible"),  # g cm^2 meant
        (_bad(max_speed=6000), "max_speed", "'3000 rpm'"),  # rpm meant
        (_bad(rated_speed="7000 rpm"), "max_speed", "below the rated speed"),
        (_bad(peak_torque=1.0), "peak_torque", "below the rated torque"),
        (_bad(ratedTorque=1.0), "ratedTorque", "unknown field"),
        (_bad(coulomb=5.0), "coulomb", "peak torque"),
        (_bad(rated_torque=[1, 2]), "rated_torque", "expected a number"),
    ],
)
def test_malformed_motor_names_entry_and_field(tmp_path, motor, field, needle):
    path = _yaml(tmp_path, [GOOD_MOTOR | {"name": "M0"}, motor])
    with pytest.raises(CatalogError) as err:
        load_catalog(path)
    e = err.value
    assert e.entry == "motor 'M1'" and e.field == field, str(e)
    assert needle in str(e) and str(path) in str(e)


@pytest.mark.parametrize(
    ("change", "field", "needle"),
    [
        ({"efficiency": 90}, "efficiency", "'90 %'"),
        ({"efficiency": 0}, "efficiency", "> 0"),
        ({"ratio": 0.5}, "ratio", "outside any plausible"),
        ({"max_input_speed": None}, "max_input_speed", "missing"),
        ({"peak_torque": 10}, "peak_torque", "below the rated torque"),
    ],
)
def test_malformed_gearbox_names_entry_and_field(tmp_path, change, field, needle):
    g = {
        "name": "G1",
        "ratio": 10,
        "efficiency": 0.95,
        "rated_torque": 20,
        "peak_torque": 40,
        "max_input_speed": "6000 rpm",
        "inertia": 1e-5,
    }
    for k, v in change.items():
        if v is None:
            g.pop(k)
        else:
            g[k] = v
    with pytest.raises(CatalogError) as err:
        load_catalog(_yaml(tmp_path, gearboxes=[g]))
    assert err.value.entry == "gearbox 'G1'" and err.value.field == field
    assert needle in str(err.value)


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("motors: [1, 2]", "motor #1: expected a mapping"),
        ("- a\n- b\n", "expected a mapping with a 'motors'"),
        ("motors: {name: x}", "field 'motors': expected a list"),
        ("motorz: []", "expected a mapping with a 'motors'"),
        ("motors: []\nextra: 1", "field 'extra': unknown top-level key"),
        ("motors: [{rated_torque: 1}]", "motor #1: field 'name': missing"),
        ("motors: [\n", "not valid YAML"),
        ("motors: []", "no motors and no gearboxes"),
    ],
)
def test_malformed_files(tmp_path, text, needle):
    path = tmp_path / "bad.yaml"
    path.write_text(textwrap.dedent(text))
    with pytest.raises(CatalogError, match="bad.yaml") as err:
        load_catalog(path)
    assert needle in str(err.value)


def test_duplicates_and_unreadable_files(tmp_path):
    with pytest.raises(CatalogError, match="motor 'M1': field 'name': appears twice"):
        load_catalog(_yaml(tmp_path, [GOOD_MOTOR, GOOD_MOTOR]))
    with pytest.raises(CatalogError, match="cannot be read"):
        load_catalog(tmp_path / "missing.yaml")
    csv_path = tmp_path / "short.csv"
    csv_path.write_text("name,rated_torque\nM1\n")
    with pytest.raises(CatalogError, match="row 2: 1 cells for 2 columns"):
        load_catalog(csv_path)
