"""Motor and gearbox catalogs: schema, units, plausibility checks, the shipped example.

A catalog is a YAML file with a ``motors`` and / or a ``gearboxes`` list, or a CSV file of one
kind (a header row of field names; gearboxes are recognised by a ``ratio`` column). Values are
SI numbers, or strings with a unit (``"3000 rpm"``, ``"0.4 kg cm^2"``, ``"90 %"``); a CSV
header may carry the unit of its column in brackets (``max_speed [rpm]``). See
:data:`MOTOR_FIELDS` and :data:`GEARBOX_FIELDS` for the fields, their units and whether they
are required; the reference with an example is in the user guide (``docs/guide/drives.md``).

Motor envelope (a simplified one, from the catalog's corner points): the peak torque is
available up to the rated speed and falls linearly to the rated torque at the maximum speed;
the continuous torque is the rated torque up to the rated speed and falls linearly to zero at
the maximum speed (:meth:`Motor.peak_torque_at`, :meth:`Motor.continuous_torque_at`).

The example catalog shipped with pkdyn (:func:`example_catalog`) holds round generic numbers
in the range of industrial servo motors and planetary gearboxes, for illustration only: they
are no vendor's data.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from pkdyn.exceptions import CatalogError
from pkdyn.files import read_text

__all__ = [
    "EXAMPLE",
    "GEARBOX_FIELDS",
    "MAX_CATALOG_BYTES",
    "MAX_CATALOG_ENTRIES",
    "MOTOR_FIELDS",
    "Catalog",
    "Field",
    "Gearbox",
    "Motor",
    "example_catalog",
    "load_catalog",
]

MAX_CATALOG_BYTES = 2_000_000
"""Largest catalog file read [bytes] (about 6,000 entries; YAML is read at about 1 MB/s)."""

MAX_CATALOG_ENTRIES = 10_000
"""Most motors (and most gearboxes) in one catalog."""

EXAMPLE = "example"
"""Name that stands for the example catalog shipped with pkdyn (CLI ``--catalog example``)."""

_RPM = 2.0 * math.pi / 60.0
_UNITS: dict[str, dict[str, float]] = {
    "N m": {"n m": 1.0, "nm": 1.0, "n.m": 1.0, "n*m": 1.0, "mn m": 1e-3, "mnm": 1e-3},
    "rad/s": {"rad/s": 1.0, "rpm": _RPM, "1/min": _RPM, "min^-1": _RPM, "r/min": _RPM},
    "kg m^2": {
        "kg m^2": 1.0,
        "kg m2": 1.0,
        "kgm^2": 1.0,
        "kgm2": 1.0,
        "kg cm^2": 1e-4,
        "kg cm2": 1e-4,
        "kgcm^2": 1e-4,
        "kgcm2": 1e-4,
        "g cm^2": 1e-7,
        "g cm2": 1e-7,
        "gcm^2": 1e-7,
        "gcm2": 1e-7,
    },
    "kg": {"kg": 1.0, "g": 1e-3},
    "s": {"s": 1.0, "min": 60.0, "h": 3600.0},
    "ohm": {"ohm": 1.0, "ohms": 1.0, "Ω": 1.0},
    "N m/A": {"n m/a": 1.0, "nm/a": 1.0, "mn m/a": 1e-3, "mnm/a": 1e-3},
    "N m s/rad": {"n m s/rad": 1.0, "nms/rad": 1.0},
    "1": {"": 1.0, "%": 1e-2},
}


@dataclass(frozen=True)
class Field:
    """One catalog field.

    Attributes:
        name: Field name (YAML key, CSV column).
        unit: SI unit of the stored value (a key of the unit table).
        lo: Smallest plausible value (SI).
        hi: Largest plausible value (SI).
        required: Must be given.
        open_lo: The value must exceed ``lo`` (else ``lo`` itself is allowed).
        meaning: What it is.

    """

    name: str
    unit: str
    lo: float
    hi: float
    required: bool
    open_lo: bool
    meaning: str


MOTOR_FIELDS = (
    Field("rated_torque", "N m", 1e-4, 1e4, True, True, "continuous (S1) torque"),
    Field("peak_torque", "N m", 1e-4, 3e4, True, True, "peak torque"),
    Field("rated_speed", "rad/s", 1.0, 1e4, True, True, "rated speed"),
    Field("max_speed", "rad/s", 1.0, 1e4, True, True, "maximum speed"),
    Field("rotor_inertia", "kg m^2", 1e-9, 10.0, True, True, "rotor inertia"),
    Field("mass", "kg", 1e-3, 1e4, True, True, "mass"),
    Field("torque_constant", "N m/A", 1e-3, 1e2, False, True, "torque constant"),
    Field("resistance", "ohm", 1e-3, 1e3, False, True, "winding resistance"),
    Field("thermal_time_constant", "s", 1.0, 1e5, False, True, "thermal time constant"),
    Field("price", "1", 0.0, 1e9, False, False, "price (any currency, the same everywhere)"),
    Field("viscous", "N m s/rad", 0.0, 1e2, False, False, "viscous friction"),
    Field("coulomb", "N m", 0.0, 1e3, False, False, "Coulomb friction"),
)
"""Motor fields: SI unit, plausible range, required or optional."""

GEARBOX_FIELDS = (
    Field("ratio", "1", 1.0, 1e4, True, False, "reduction (input speed / output speed)"),
    Field("efficiency", "1", 0.0, 1.0, True, True, "efficiency when the motor drives"),
    Field("rated_torque", "N m", 1e-3, 1e6, True, True, "rated (nominal) output torque"),
    Field("peak_torque", "N m", 1e-3, 3e6, True, True, "peak (acceleration) output torque"),
    Field("max_input_speed", "rad/s", 1.0, 1e4, True, True, "maximum input speed"),
    Field("inertia", "kg m^2", 0.0, 10.0, True, False, "inertia at the input"),
    Field("backdrive_efficiency", "1", 0.0, 1.0, False, True, "efficiency when back-driven"),
    Field("mass", "kg", 1e-3, 1e4, False, True, "mass"),
    Field("price", "1", 0.0, 1e9, False, False, "price"),
)
"""Gearbox fields: SI unit, plausible range, required or optional."""


@dataclass(frozen=True)
class Motor:
    """A motor of a catalog (SI units; see :data:`MOTOR_FIELDS`)."""

    name: str
    rated_torque: float
    peak_torque: float
    rated_speed: float
    max_speed: float
    rotor_inertia: float
    mass: float
    torque_constant: float | None = None
    resistance: float | None = None
    thermal_time_constant: float | None = None
    price: float | None = None
    viscous: float = 0.0
    coulomb: float = 0.0

    def peak_torque_at(self, omega: float | np.ndarray) -> np.ndarray:
        """Peak-envelope torque [N m] at motor speeds ``omega`` [rad/s] (0 beyond max speed)."""
        w = np.abs(np.asarray(omega, dtype=float))
        span = max(self.max_speed - self.rated_speed, 1e-12)
        fall = self.peak_torque + (self.rated_torque - self.peak_torque) * (
            (w - self.rated_speed) / span
        )
        out = np.where(w <= self.rated_speed, self.peak_torque, fall)
        return np.where(w <= self.max_speed * (1.0 + 1e-12), out, 0.0)

    def continuous_torque_at(self, omega: float | np.ndarray) -> np.ndarray:
        """Continuous-envelope torque [N m] at motor speeds ``omega`` [rad/s]."""
        w = np.abs(np.asarray(omega, dtype=float))
        span = max(self.max_speed - self.rated_speed, 1e-12)
        fall = self.rated_torque * (self.max_speed - w) / span
        out = np.where(w <= self.rated_speed, self.rated_torque, fall)
        return np.clip(out, 0.0, None)


@dataclass(frozen=True)
class Gearbox:
    """A gearbox of a catalog (SI units; see :data:`GEARBOX_FIELDS`)."""

    name: str
    ratio: float
    efficiency: float
    rated_torque: float
    peak_torque: float
    max_input_speed: float
    inertia: float
    backdrive_efficiency: float | None = None
    mass: float | None = None
    price: float | None = None


@dataclass(frozen=True)
class Catalog:
    """Motors and gearboxes, with the files they came from."""

    motors: tuple[Motor, ...] = ()
    gearboxes: tuple[Gearbox, ...] = ()
    source: str = ""

    def __add__(self, other: Catalog) -> Catalog:
        src = " + ".join(s for s in (self.source, other.source) if s)
        return Catalog(self.motors + other.motors, self.gearboxes + other.gearboxes, src)


def _value(source: str, entry: str, f: Field, raw: Any, column_unit: str | None) -> float:
    """A field's SI value from a number or a string with a unit."""
    table = _UNITS[f.unit]
    unit = column_unit
    if isinstance(raw, bool):
        raise CatalogError(source, entry, f.name, f"expected a number, got {raw!r}")
    if isinstance(raw, int | float):
        number = float(raw)
    elif isinstance(raw, str):
        m = re.fullmatch(r"\s*([-+0-9.eE]+(?:[eE][-+]?\d+)?)\s*(.*?)\s*", raw)
        if not m:
            raise CatalogError(source, entry, f.name, f"expected a number, got {raw!r}")
        try:
            number = float(m.group(1))
        except ValueError:
            raise CatalogError(source, entry, f.name, f"expected a number, got {raw!r}") from None
        if m.group(2):
            unit = m.group(2)
    else:
        raise CatalogError(source, entry, f.name, f"expected a number, got {raw!r}")
    scale = 1.0
    if unit is not None and unit.strip():
        key = re.sub(r"\s+", " ", unit.strip().lower()).replace("·", " ").replace("²", "^2")
        if key not in table:
            known = ", ".join(sorted({k for k in table if k}))
            raise CatalogError(
                source, entry, f.name, f"unknown unit '{unit}' for {f.meaning} (use {known})"
            )
        scale = table[key]
    inv = 1.0 / scale  # divide by 100, 1e4... (exact for decimal prefixes: 94 % -> 0.94)
    value = number / round(inv) if scale < 1.0 and abs(inv - round(inv)) < 1e-9 else number * scale
    if not math.isfinite(value):
        raise CatalogError(source, entry, f.name, f"must be finite, got {raw!r}")
    low_ok = value > f.lo if f.open_lo else value >= f.lo
    if not low_ok and value <= 0.0:
        sign = "> 0" if f.open_lo else ">= 0"
        raise CatalogError(source, entry, f.name, f"must be {sign}, got {raw!r}")
    if not low_ok or value > f.hi:
        if f.unit == "1" and f.hi == 1.0:
            raise CatalogError(
                source, entry, f.name, f"{raw!r} is not a fraction in (0, 1]; write 0.9 or '90 %'"
            )
        raise CatalogError(
            source,
            entry,
            f.name,
            f"{raw!r} is outside any plausible {f.meaning} ([{f.lo:g}, {f.hi:g}] {f.unit}); "
            f"check its unit (plain numbers are SI: {f.unit})",
        )
    return value


def _entry(
    source: str,
    kind: str,
    index: int,
    raw: Any,
    specs: tuple[Field, ...],
    units: Mapping[str, str] | None = None,
) -> dict[str, Any]:
    if not isinstance(raw, Mapping):
        raise CatalogError(source, f"{kind} #{index + 1}", None, "expected a mapping of fields")
    name = raw.get("name")
    if name is None or str(name).strip() == "":
        raise CatalogError(source, f"{kind} #{index + 1}", "name", "missing")
    entry = f"{kind} '{name}'"
    known = {f.name for f in specs} | {"name"}
    for key in raw:
        if str(key) not in known:
            raise CatalogError(
                source, entry, str(key), f"unknown field (known: {', '.join(sorted(known))})"
            )
    out: dict[str, Any] = {"name": str(name)}
    for f in specs:
        value = raw.get(f.name)
        if value is None or (isinstance(value, str) and not value.strip()):
            if f.required:
                raise CatalogError(source, entry, f.name, f"missing ({f.meaning}, {f.unit})")
            continue
        out[f.name] = _value(source, entry, f, value, (units or {}).get(f.name))
    return out


def _motor(source: str, index: int, raw: Any, units: Mapping[str, str] | None = None) -> Motor:
    d = _entry(source, "motor", index, raw, MOTOR_FIELDS, units)
    entry = f"motor '{d['name']}'"
    if d["peak_torque"] < d["rated_torque"]:
        raise CatalogError(
            source, entry, "peak_torque", f"below the rated torque ({d['rated_torque']:g} N m)"
        )
    if d["max_speed"] < d["rated_speed"]:
        raise CatalogError(
            source, entry, "max_speed", f"below the rated speed ({d['rated_speed']:g} rad/s)"
        )
    accel = d["peak_torque"] / d["rotor_inertia"]
    if not 50.0 <= accel <= 1e7:
        raise CatalogError(
            source,
            entry,
            "rotor_inertia",
            f"peak torque / rotor inertia = {accel:.3g} rad/s^2 is implausible for a motor "
            "(50 to 1e7); check the unit of rotor_inertia (plain numbers are kg m^2; write "
            "e.g. '0.4 kg cm^2')",
        )
    for key, torque, limit in (
        ("rated_speed", "rated_torque", 3e3),
        ("max_speed", "peak_torque", 8e3),
    ):
        power = d[torque] * d[key] / d["mass"]
        if power > limit:
            raise CatalogError(
                source,
                entry,
                key,
                f"{torque} x {key} / mass = {power:.3g} W/kg is implausible for a motor (above "
                f"{limit / 1e3:g} kW/kg); check the units of {key} (plain numbers are rad/s; "
                "write e.g. '3000 rpm') and of mass",
            )
    if d.get("coulomb", 0.0) >= d["peak_torque"]:
        raise CatalogError(source, entry, "coulomb", "friction at or above the peak torque")
    return Motor(**d)


def _gearbox(source: str, index: int, raw: Any, units: Mapping[str, str] | None = None) -> Gearbox:
    d = _entry(source, "gearbox", index, raw, GEARBOX_FIELDS, units)
    if d["peak_torque"] < d["rated_torque"]:
        raise CatalogError(
            source,
            f"gearbox '{d['name']}'",
            "peak_torque",
            f"below the rated torque ({d['rated_torque']:g} N m)",
        )
    return Gearbox(**d)


def _unique(source: str, kind: str, names: list[str]) -> None:
    seen: set[str] = set()
    for n in names:
        if n in seen:
            raise CatalogError(source, f"{kind} '{n}'", "name", "appears twice")
        seen.add(n)


def _from_yaml(text: str, source: str) -> Catalog:
    try:
        data = yaml.load(text, Loader=getattr(yaml, "CSafeLoader", yaml.SafeLoader))
    except yaml.YAMLError as err:
        raise CatalogError(source, None, None, f"not valid YAML ({err})") from None
    except RecursionError:
        raise CatalogError(source, None, None, "nested too deeply to be a catalog") from None
    if not isinstance(data, Mapping) or not (
        "motors" in data or "gearboxes" in data
    ):  # a list alone is ambiguous
        raise CatalogError(
            source, None, None, "expected a mapping with a 'motors' and / or 'gearboxes' list"
        )
    for key in data:
        if key not in ("motors", "gearboxes", "note", "schema"):
            raise CatalogError(
                source, None, str(key), "unknown top-level key (motors, gearboxes, note, schema)"
            )
    lists = {}
    for key in ("motors", "gearboxes"):
        items = data.get(key) or []
        if not isinstance(items, list):
            raise CatalogError(source, None, key, "expected a list of entries")
        if len(items) > MAX_CATALOG_ENTRIES:
            raise CatalogError(
                source, None, key, f"{len(items)} entries, more than {MAX_CATALOG_ENTRIES}"
            )
        lists[key] = items
    motors = tuple(_motor(source, i, m) for i, m in enumerate(lists["motors"]))
    gears = tuple(_gearbox(source, i, g) for i, g in enumerate(lists["gearboxes"]))
    return Catalog(motors, gears, source)


def _from_csv(text: str, source: str) -> Catalog:
    lines = (line for line in text.lstrip("\ufeff").splitlines() if not line.startswith("#"))
    try:
        rows = list(csv.reader(lines))
    except csv.Error as err:  # a cell beyond the csv module's field limit, a NUL byte
        raise CatalogError(source, None, None, f"not a CSV table ({err})") from None
    rows = [r for r in rows if any(c.strip() for c in r)]
    if not rows:
        raise CatalogError(source, None, None, "empty CSV file (expected a header row)")
    names: list[str] = []
    units: dict[str, str] = {}
    for cell in rows[0]:
        m = re.fullmatch(r"\s*([A-Za-z_]+)\s*(?:\[(.*)\])?\s*", cell)
        if not m:
            raise CatalogError(source, "header", cell, "expected 'field' or 'field [unit]'")
        names.append(m.group(1))
        if m.group(2):
            units[m.group(1)] = m.group(2)
    gear = "ratio" in names
    if len(rows) - 1 > MAX_CATALOG_ENTRIES:
        raise CatalogError(
            source, None, None, f"{len(rows) - 1} entries, more than {MAX_CATALOG_ENTRIES}"
        )
    out_m: list[Motor] = []
    out_g: list[Gearbox] = []
    for i, row in enumerate(rows[1:]):
        if len(row) != len(names):
            raise CatalogError(
                source,
                f"row {i + 2}",
                None,
                f"{len(row)} cells for {len(names)} columns",
            )
        raw = {k: v.strip() for k, v in zip(names, row, strict=True) if v.strip() != ""}
        if gear:
            out_g.append(_gearbox(source, i, raw, units))
        else:
            out_m.append(_motor(source, i, raw, units))
    return Catalog(tuple(out_m), tuple(out_g), source)


def load_catalog(path: str | Path) -> Catalog:
    """Read a motor / gearbox catalog (YAML or CSV; ``example``: the shipped example).

    Args:
        path: The file, or :data:`EXAMPLE`.

    Returns:
        Its motors and gearboxes (SI units).

    Raises:
        CatalogError: Unreadable file (or not a regular file: a FIFO, a device; or larger than
            :data:`MAX_CATALOG_BYTES`), unknown field or unit, missing field, or a value that is
            not positive or outside any plausible range (the message names the entry, the field
            and the likely fix).

    """
    if str(path) == EXAMPLE:
        return example_catalog()
    p = Path(path)
    source = str(path)
    text = read_text(p, MAX_CATALOG_BYTES, lambda msg: CatalogError(source, None, None, msg))
    cat = _from_csv(text, source) if p.suffix.lower() == ".csv" else _from_yaml(text, source)
    _unique(source, "motor", [m.name for m in cat.motors])
    _unique(source, "gearbox", [g.name for g in cat.gearboxes])
    if not cat.motors and not cat.gearboxes:
        raise CatalogError(source, None, None, "no motors and no gearboxes")
    return cat


def example_catalog() -> Catalog:
    """The example catalog shipped with pkdyn: 7 servo motors, 18 planetary gearboxes.

    Round generic numbers in the range of industrial products, for illustration only (no
    vendor's data).

    Returns:
        The catalog (source ``example``).

    """
    res = resources.files("pkdyn.dynamics") / "catalogs" / "example.yaml"
    cat = _from_yaml(res.read_text(encoding="utf-8"), "example catalog")
    return Catalog(cat.motors, cat.gearboxes, EXAMPLE)
