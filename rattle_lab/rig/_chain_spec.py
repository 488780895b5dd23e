"""The scene's ``[chain]`` table: a realistic measurement chain for the synthetic rig (opt-in).

The spec and its parser; :mod:`rattle_lab.rig._chain` applies it to the channels.

Each effect is off by default; a scene turns on what it wants:

* ``decoder_delay_s``: the vibrometer decoder's group delay (a band-limited fractional
  delay of the velocity); the record declares it (``group_delay_s``, schema v2);
* ``vibrometer = "absolute"``: the panel alone, the base velocity not subtracted (declared
  as ``measurand = "panel_absolute"``; default ``"relative"``, a differential vibrometer);
* ``ring_velocity_per_m_s``: the plate's next modes (the scene's ``ringing_freqs_hz``)
  ringing in the vibrometer after each impact, excited by its impulse: a velocity step of
  this many m/s per m/s of velocity change, decaying with ``ringing_decay_s``;
* ``hum_hz`` with ``hum_m_s``, ``hum_m_s2``, ``hum_pa``: mains hum in the vibrometer, the
  accelerometers and the microphone;
* ``offset_velocity_m_s``, ``offset_plate_m_s2``, ``offset_base_m_s2``, ``offset_mic_pa``:
  DC offsets;
* ``adc_bits`` (16 or 24; 0 = off): quantisation over each channel's input range (or
  1.25 times its largest sample when it has none);
* ``floor_extra_path_m`` and ``floor_gain``: one floor reflection of the sound, arriving
  ``floor_extra_path_m / c`` after the direct sound (the microphone's distance and
  propagation delay are the ``[acoustic]`` table's).

Background noise is each sensor's ``noise_rms``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

VIBROMETERS = ("relative", "absolute")
ADC_BITS = (0, 16, 24)


@dataclass(frozen=True)
class ChainSpec:
    """The measurement chain (see the module docstring); every default is "off"."""

    decoder_delay_s: float = 0.0
    vibrometer: str = "relative"
    ring_velocity_per_m_s: float = 0.0
    hum_hz: float = 50.0
    hum_m_s: float = 0.0
    hum_m_s2: float = 0.0
    hum_pa: float = 0.0
    offset_velocity_m_s: float = 0.0
    offset_plate_m_s2: float = 0.0
    offset_base_m_s2: float = 0.0
    offset_mic_pa: float = 0.0
    adc_bits: int = 0
    floor_extra_path_m: float = 0.0
    floor_gain: float = 0.0

    @property
    def measurand(self) -> str:
        """The velocity channel's ``measurand`` attribute."""
        return "panel_absolute" if self.vibrometer == "absolute" else "panel_relative_to_striker"


def parse_chain(reader: Any) -> ChainSpec:
    """A :class:`ChainSpec` from the scene's ``[chain]`` table reader (``_scene._Reader``)."""
    r = reader
    spec = ChainSpec(
        decoder_delay_s=r.number("decoder_delay_s", 0.0, low=0.0),
        vibrometer=r.string("vibrometer", "relative"),
        ring_velocity_per_m_s=r.number("ring_velocity_per_m_s", 0.0, low=0.0),
        hum_hz=r.positive("hum_hz", 50.0),
        hum_m_s=r.number("hum_m_s", 0.0, low=0.0), hum_m_s2=r.number("hum_m_s2", 0.0, low=0.0),
        hum_pa=r.number("hum_pa", 0.0, low=0.0),
        offset_velocity_m_s=r.number("offset_velocity_m_s", 0.0),
        offset_plate_m_s2=r.number("offset_plate_m_s2", 0.0),
        offset_base_m_s2=r.number("offset_base_m_s2", 0.0),
        offset_mic_pa=r.number("offset_mic_pa", 0.0),
        adc_bits=r.integer("adc_bits", 0, low=0),
        floor_extra_path_m=r.number("floor_extra_path_m", 0.0, low=0.0),
        floor_gain=r.number("floor_gain", 0.0, low=0.0))
    if spec.vibrometer not in VIBROMETERS:
        r.fail(r.key("vibrometer"), spec.vibrometer, f"must be one of {VIBROMETERS}")
    if spec.adc_bits not in ADC_BITS:
        r.fail(r.key("adc_bits"), spec.adc_bits, "must be 0 (off), 16 or 24")
    if spec.floor_gain > 1.0:
        r.fail(r.key("floor_gain"), spec.floor_gain, "must be <= 1 (a reflection loses energy)")
    r.done()
    return spec
