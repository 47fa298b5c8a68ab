"""Units accepted on input: the SI unit each parameter expects, or a plain multiple of it.

xbsm computes in SI. An input DataArray may say in its ``units`` attribute that it is
in another unit of the same kind (``"km"`` for a ground range, ``"um"`` for a pitch,
``"mrad"`` or ``"deg"`` for an angle, ``"ms"`` for a time); it is converted on input.
Any other unit is refused with a message naming the unit expected: a value is never
reinterpreted silently. A few hand-written rules cover what the parameters need, so no
units library is required.
"""

from __future__ import annotations

import math
from types import MappingProxyType

__all__ = ["accepted", "in_units", "si_factor"]

#: Decimal prefixes accepted on the base units m, s and rad.
_PREFIXES = MappingProxyType(
    {"": 1.0, "k": 1e3, "c": 1e-2, "m": 1e-3, "u": 1e-6, "\u00b5": 1e-6, "n": 1e-9})
_BASES = ("m", "s", "rad")
#: Other spellings, and units that are a fixed multiple of a base unit.
_ALIASES = MappingProxyType({
    "meter": "m", "metre": "m", "meters": "m", "metres": "m",
    "kilometer": "km", "kilometre": "km", "kilometers": "km", "kilometres": "km",
    "micron": "um", "microns": "um", "micrometer": "um", "micrometre": "um",
    "nanometer": "nm", "nanometre": "nm", "millimeter": "mm", "millimetre": "mm",
    "second": "s", "seconds": "s", "sec": "s",
    "radian": "rad", "radians": "rad", "kelvin": "K",
    "m/s": "m s-1", "rad/s": "rad s-1", "1/s": "s-1", "electrons/s": "s-1",
    "dimensionless": "1",
})
_MULTIPLES = MappingProxyType({
    "deg": ("rad", math.pi / 180.0), "degree": ("rad", math.pi / 180.0),
    "degrees": ("rad", math.pi / 180.0), "km/h": ("m s-1", 1.0 / 3.6),
    "mrad/s": ("rad s-1", 1e-3), "urad/s": ("rad s-1", 1e-6),
})


def _scale(unit: str):
    """(base, factor to the base) of a prefixed base unit, or None."""
    unit = _ALIASES.get(unit, unit)
    if unit in _MULTIPLES:
        return _MULTIPLES[unit]
    for base in _BASES:
        prefix = unit[: len(unit) - len(base)]
        if unit.endswith(base) and prefix in _PREFIXES:
            return base, _PREFIXES[prefix]
    return unit, 1.0


def si_factor(given: str, expected: str) -> float | None:
    """Factor that converts a value in ``given`` units to ``expected`` units, or None.

    Parameters
    ----------
    given : str
        The input's ``units`` attribute, e.g. ``"km"``.
    expected : str
        The unit xbsm expects for the parameter, e.g. ``"m"``.

    Returns
    -------
    float or None
        ``value_in_expected = value_in_given * factor``; None when the two are not
        multiples of one another.
    """
    base_given, f_given = _scale(given.strip())
    base_expected, f_expected = _scale(expected)
    if base_given != base_expected:
        return None
    return f_given / f_expected


def accepted(expected: str) -> list[str]:
    """Examples of ``units`` attributes accepted for a parameter in ``expected`` units."""
    base, _ = _scale(expected)
    if base in _BASES:
        out = [prefix + base for prefix in ("k", "", "m", "u", "n") if prefix + base != expected]
        return out + (["deg"] if base == "rad" else [])
    return [unit for unit, (b, _) in _MULTIPLES.items() if b == base][:2] or [expected]


def in_units(name: str, value, expected: str):
    """``value`` (a DataArray) in ``expected`` units, by its ``units`` attribute if it has one.

    Raises
    ------
    ValueError
        Naming ``name``, the unit given and the unit expected, when the two are not
        multiples of one another.
    """
    given = value.attrs.get("units")
    if given is None or str(given).strip() in (expected, ""):
        return value
    factor = si_factor(str(given).strip(), expected)
    if factor is None:
        raise ValueError(
            f"{name} has units {given!r}; xbsm expects {expected!r} "
            f"(or one of {', '.join(accepted(expected))}), converted on input")
    return value * factor
