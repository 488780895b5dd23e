"""Units of the rattle record and their conversion to SI.

Every channel is stored in the units its writer chose (``units``); reading
converts it to the SI unit of its quantity by one linear factor,
``value_si = scale_to_si * value_stored`` (no offsets: every transducer of the
rig is AC-coupled or zero-based).  Raw volts (``units == "V"``) are converted
with the channel's ``sensitivity`` in ``sensitivity_units``.

The unit strings here and the enums of the JSON Schema must agree; a test
pins that.
"""

from __future__ import annotations

from typing import Literal

from rattle_lab.exceptions import SchemaError

#: Standard acceleration of gravity, m/s^2 (3rd CGPM, 1901; exact by definition).
G0_MS2 = 9.80665

Quantity = Literal["base_acceleration", "plate_acceleration", "plate_velocity",
                   "sound_pressure", "drive_signal", "excitation_force"]

QUANTITIES: tuple[str, ...] = ("base_acceleration", "plate_acceleration", "plate_velocity",
                               "sound_pressure", "drive_signal", "excitation_force")

#: SI unit of each quantity (as written in the store and the catalogue).
SI_UNITS: dict[str, str] = {
    "base_acceleration": "m/s^2",
    "plate_acceleration": "m/s^2",
    "plate_velocity": "m/s",
    "sound_pressure": "Pa",
    "drive_signal": "V",
    "excitation_force": "N",
}

#: Factor from a stored unit to the SI unit of its quantity ("V" of a drive signal
#: is already SI; "V" of a transducer goes through its sensitivity instead).
UNIT_TO_SI: dict[str, float] = {
    "m/s^2": 1.0,
    "m/s\u00b2": 1.0,
    "g": G0_MS2,
    "m/s": 1.0,
    "mm/s": 1e-3,
    "Pa": 1.0,
    "V": 1.0,
    "mV": 1e-3,
    "N": 1.0,
    "1": 1.0,
}

#: Stored units allowed for each quantity.  "1" means uncalibrated (full scale).
ALLOWED_UNITS: dict[str, tuple[str, ...]] = {
    "base_acceleration": ("m/s^2", "m/s\u00b2", "g", "V", "1"),
    "plate_acceleration": ("m/s^2", "m/s\u00b2", "g", "V", "1"),
    "plate_velocity": ("m/s", "mm/s", "V", "1"),
    "sound_pressure": ("Pa", "V", "1"),
    "drive_signal": ("V", "mV", "1"),
    "excitation_force": ("N", "V", "1"),
}

#: Sensitivity units: (direction, factor).  "volts_per_si": the sensitivity S
#: gives S*factor volts per SI unit, so value_si = volts / (S*factor);
#: "si_per_volt": S*factor SI units per volt, so value_si = volts * S*factor.
SENSITIVITY_UNITS: dict[str, tuple[Literal["volts_per_si", "si_per_volt"], float]] = {
    "mV/g": ("volts_per_si", 1e-3 / G0_MS2),
    "V/g": ("volts_per_si", 1.0 / G0_MS2),
    "mV/(m/s^2)": ("volts_per_si", 1e-3),
    "mV/(m/s\u00b2)": ("volts_per_si", 1e-3),
    "V/(m/s^2)": ("volts_per_si", 1.0),
    "V/(m/s\u00b2)": ("volts_per_si", 1.0),
    "(mm/s)/V": ("si_per_volt", 1e-3),
    "(m/s)/V": ("si_per_volt", 1.0),
    "mV/(mm/s)": ("volts_per_si", 1.0),  # 1 mV per 1 mm/s is 1 V per m/s
    "V/(m/s)": ("volts_per_si", 1.0),
    "mV/Pa": ("volts_per_si", 1e-3),
    "V/Pa": ("volts_per_si", 1.0),
    "mV/N": ("volts_per_si", 1e-3),
    "V/N": ("volts_per_si", 1.0),
}

#: Sensitivity units allowed for each transducer quantity.
ALLOWED_SENSITIVITY_UNITS: dict[str, tuple[str, ...]] = {
    "base_acceleration": ("mV/g", "V/g", "mV/(m/s^2)", "mV/(m/s\u00b2)", "V/(m/s^2)", "V/(m/s\u00b2)"),
    "plate_acceleration": ("mV/g", "V/g", "mV/(m/s^2)", "mV/(m/s\u00b2)", "V/(m/s^2)", "V/(m/s\u00b2)"),
    "plate_velocity": ("(mm/s)/V", "(m/s)/V", "mV/(mm/s)", "V/(m/s)"),
    "sound_pressure": ("mV/Pa", "V/Pa"),
    "excitation_force": ("mV/N", "V/N"),
}


def scale_to_si(quantity: str, units: str, sensitivity: float | None = None,
                sensitivity_units: str | None = None, *, where: str = "") -> tuple[float, str]:
    """Return ``(scale, si_units)`` with ``value_si = scale * value_stored``.

    Parameters
    ----------
    quantity : str
        One of :data:`QUANTITIES`.
    units : str
        The stored units (one of ``ALLOWED_UNITS[quantity]``).
    sensitivity : float, optional
        Transducer sensitivity, required when ``units == "V"`` for a transducer.
    sensitivity_units : str, optional
        Units of ``sensitivity`` (one of ``ALLOWED_SENSITIVITY_UNITS[quantity]``).
    where : str
        Place named in error messages (``"file: /hdf5/path"``).

    Returns
    -------
    scale : float
        Factor from stored units to SI.
    si_units : str
        ``SI_UNITS[quantity]``, or ``"1"`` for uncalibrated data.

    Raises
    ------
    SchemaError
        If the units do not fit the quantity or a needed sensitivity is missing.

    Examples
    --------
    >>> import numpy as np
    >>> scale, unit = scale_to_si("base_acceleration", "V", 100.0, "mV/g")
    >>> unit, bool(np.isclose(scale * 0.1, 9.80665))   # 100 mV at 100 mV/g is 1 g
    ('m/s^2', True)
    >>> scale_to_si("plate_velocity", "V", 25.0, "(mm/s)/V")[0]   # 25 mm/s per volt
    0.025
    """
    prefix = f"{where}: " if where else ""
    if quantity not in SI_UNITS:
        raise SchemaError(f"{prefix}attribute 'quantity': unknown quantity {quantity!r}")
    if units not in ALLOWED_UNITS[quantity]:
        raise SchemaError(f"{prefix}attribute 'units': {units!r} is not a unit of {quantity} "
                          f"(allowed: {', '.join(ALLOWED_UNITS[quantity])})")
    if units == "1":
        return 1.0, "1"
    if units == "V" and quantity != "drive_signal":
        if sensitivity is None or sensitivity_units is None:
            raise SchemaError(f"{prefix}attribute 'sensitivity': raw volts need sensitivity "
                              "and sensitivity_units")
        if sensitivity_units not in ALLOWED_SENSITIVITY_UNITS[quantity]:
            raise SchemaError(f"{prefix}attribute 'sensitivity_units': {sensitivity_units!r} "
                              f"does not fit {quantity}")
        if not sensitivity > 0:
            raise SchemaError(f"{prefix}attribute 'sensitivity': must be > 0, was {sensitivity}")
        direction, factor = SENSITIVITY_UNITS[sensitivity_units]
        if direction == "volts_per_si":
            return 1.0 / (sensitivity * factor), SI_UNITS[quantity]
        return sensitivity * factor, SI_UNITS[quantity]
    return UNIT_TO_SI[units], SI_UNITS[quantity]


def canonical_unit(unit: str) -> str:
    """Spell a unit the ASCII way (``m/s²`` -> ``m/s^2``)."""
    return unit.replace("\u00b2", "^2")
