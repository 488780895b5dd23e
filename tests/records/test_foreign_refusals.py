"""Issue 28, item 4: each foreign reader refuses what it does not handle in one clear line.

``data_schema/README.md`` ("What each foreign reader handles") lists what LVM, TDMS, WAV,
MAT, UFF and NPY files may hold.  Here, per format, files a user could bring that fall
outside it: each must raise a :class:`RattleLabError` subclass whose message is one line
naming the file and the field (header, attribute, key or property) at fault, and the CLI
must print that line and exit 2.  (The LVM header refusals are in ``test_lvm_spec.py``.)
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
import soundfile as sf
from nptdms import ChannelObject, GroupObject, RootObject, TdmsWriter

from rattle_lab.exceptions import FileFormatError, RattleLabError
from rattle_lab.records import read
from rattle_lab.records._errors import MappingError
from record_factory import run_command
from test_readers import MAT_MAPPING, make_mat


def _mat_v5(tmp: Path) -> tuple[Path, Path | None]:
    path = tmp / "lab.mat"      # a level-5 MAT-file header (what save() writes before -v7.3)
    path.write_bytes(b"MATLAB 5.0 MAT-file, Platform: GLNXA64, Created on: Mon Mar  4 2024"
                     .ljust(116) + b"\x00" * 8 + b"\x00\x01IM" + b"\x00" * 64)
    return path, None


def _mat_char_channel(tmp: Path) -> tuple[Path, Path | None]:
    path = tmp / "lab.mat"
    make_mat(path)
    mapping = tmp / "m.toml"     # the operator's name (MATLAB text: uint16) chosen as samples
    mapping.write_text(MAT_MAPPING.replace('source = "/acc"', 'source = "/meta/operator"'))
    return path, mapping


def _npz(tmp: Path) -> tuple[Path, Path | None]:
    path = tmp / "lab.npz"
    np.savez(path, force=np.zeros(10), acc=np.ones(10))
    return path, None


def _npy_complex(tmp: Path) -> tuple[Path, Path | None]:
    path = tmp / "frf.npy"
    np.save(path, np.ones((2, 8), dtype=complex))
    mapping = tmp / "m.toml"
    mapping.write_text(NPY_MAPPING)
    return path, mapping


def _wav_index(tmp: Path) -> tuple[Path, Path | None]:
    path = tmp / "room.wav"
    sf.write(path, np.zeros((100, 2)), 8000, subtype="PCM_16")
    mapping = tmp / "m.toml"
    mapping.write_text(WAV_MAPPING)
    return path, mapping


def _tdms_timestamps(tmp: Path) -> tuple[Path, Path | None]:
    path = tmp / "rig.tdms"
    with TdmsWriter(path) as writer:
        writer.write_segment([
            RootObject({}), GroupObject("run1"),
            ChannelObject("run1", "when", np.array(["2024-03-01T14:05:00"] * 4,
                                                   dtype="datetime64[us]"),
                          properties={"quantity": "base_acceleration"})])
    return path, None


def _uff_not_si(tmp: Path) -> tuple[Path, Path | None]:
    import pyuff
    path = tmp / "imperial.uff"
    sets = [pyuff.prepare_164(units_code=2, units_description="BFT", temp_mode=1,
                              length=0.3048, force=4.44822, temp=1.0, temp_offset=459.67),
            pyuff.prepare_58(binary=0, func_type=1, rsp_node=1, rsp_dir=3, ref_node=0,
                             ref_dir=0, rsp_ent_name="ACC", ref_ent_name="NONE",
                             data=np.zeros(16), x=np.arange(16) / 1000.0, id1="x",
                             abscissa_spacing=1, abscissa_spec_data_type=17,
                             ordinate_spec_data_type=12, orddenom_spec_data_type=0)]
    pyuff.UFF(str(path)).write_sets(sets, mode="add")
    return path, None


NPY_MAPPING = """
[mapping]
version = 1
[campaign]
campaign_id = "c"
[rig]
apparatus = "other"
description = "x"
[[runs]]
run_id = "r"
protocol = "transient"
[[runs.channels]]
name = "force"
index = 0
quantity = "excitation_force"
units = "N"
sample_rate_hz = 1000.0
start_time_s = 0.0
"""

WAV_MAPPING = """
[mapping]
version = 1
[campaign]
campaign_id = "c"
[rig]
apparatus = "other"
description = "x"
[[runs]]
run_id = "r"
protocol = "transient"
[[runs.channels]]
name = "mic"
index = 2
quantity = "sound_pressure"
"""

Case = Callable[[Path], tuple[Path, "Path | None"]]
CASES: list[tuple[str, Case, type[RattleLabError], str]] = [
    ("mat_v5", _mat_v5, FileFormatError,
     r"lab\.mat: header: a MATLAB v5/v7 MAT-file \(not HDF5\); only v7\.3 MAT-files are read"),
    ("mat_char", _mat_char_channel, MappingError,
     r"m\.toml: runs\[0\]\.channels\[0\]: source '/meta/operator': attribute 'MATLAB_class': "
     r"'char' is not a numeric MATLAB array"),
    ("npz", _npz, FileFormatError, r"lab\.npz: header: a NumPy \.npz archive"),
    ("npy_complex", _npy_complex, FileFormatError,
     r"frf\.npy: a \.npy record must be a 1-D or 2-D numeric array, got shape \(2, 8\) dtype "
     r"complex128"),
    ("wav_index", _wav_index, MappingError,
     r"m\.toml: runs\[0\]\.channels\[0\]: key 'index': 2; the file has 2 channel\(s\)"),
    ("tdms_timestamps", _tdms_timestamps, MappingError,
     r"channel 'run1/when' has non-numeric data \(datetime64"),
    ("uff_not_si", _uff_not_si, FileFormatError,
     r"imperial\.uff: dataset 0 \(164\): units code 2 is not SI"),
]


@pytest.mark.parametrize(("make", "error", "match"),
                         [pytest.param(m, e, r, id=name) for name, m, e, r in CASES])
def test_each_reader_refuses_what_it_does_not_handle_in_one_line(tmp_path, make, error, match):
    path, mapping = make(tmp_path)
    with pytest.raises(error, match=match) as info:
        read(path, mapping=mapping) if mapping is not None else read(path)
    message = str(info.value)
    assert "\n" not in message
    assert path.name in message or (mapping is not None and mapping.name in message)
    # the CLI: the same line, exit 2, no traceback
    args = ["ingest", str(path), "-o", str(tmp_path / "s.h5")]
    proc = run_command(*args, *(["--mapping", str(mapping)] if mapping is not None else []))
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and len(proc.stderr.strip().splitlines()) == 1
    assert path.name in proc.stderr or (mapping is not None and mapping.name in proc.stderr)
