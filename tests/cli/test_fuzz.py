"""Hostile and malformed inputs (issue 16): each ends in exit 2 with one line, nothing left behind.

Hypothesis makes inputs of every kind the CLI reads (HDF5, LVM, TDMS, WAV, NPY,
mapping TOML, scene TOML, pipeline TOML), each built to be invalid (cut short,
a declared size the bytes do not hold, keys the format does not know); a
hand-made list adds the hostile HDF5 constructs (references out of the file,
1e12 declared samples) and other declared-size lies.  Every input runs through
:func:`rattle_lab.cli.main` in-process (the command's real code path, fast), in
a folder of its own, under a hang guard; a few also run through the installed
entry point.  The count of inputs tried is printed for the README.
"""

from __future__ import annotations

import contextlib
import io
import os
import signal
import struct
import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import h5py
import numpy as np
import pytest
import soundfile
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from record_factory import make_record, run_cli, write_record

from rattle_lab.cli import main

#: A command that hangs on one input fails the test after this many seconds (a hang guard,
#: not a speed assertion: the inputs fail in milliseconds).
HANG_GUARD_S = 60
MIC = "runs/dwell_094/channels/mic"
TRIED: dict[str, int] = {}

# One valid file of each kind, built once; the strategies cut or corrupt their bytes.
_ROOT = Path(tempfile.mkdtemp(prefix="rattle-fuzz-"))
_REC = write_record(_ROOT / "rec.h5", make_record(n=1024))
_WAV = _ROOT / "x.wav"
soundfile.write(_WAV, (0.5 * np.sin(np.arange(4800) / 7.0)).astype(np.float32), 48000,
                subtype="FLOAT")
_LVM_MAPPING = """[mapping]
version = 1
[campaign]
campaign_id = "fz"
[rig]
apparatus = "other"
[[runs]]
run_id = "r"
protocol = "transient"
[[runs.channels]]
name = "acc"
source = "acc"
quantity = "base_acceleration"
"""
_LVM_HEAD = ("LabVIEW Measurement\t\nSeparator\tTab\nDecimal_Separator\t.\nX_Columns\tOne\n"
             "***End_of_Header***\t\n\nChannels\t1\t\nSamples\t{n}\t\nY_Unit_Label\tm/s^2\t\n"
             "X0\t0\t\nDelta_X\t0.0005\t\n***End_of_Header***\t\t\nX_Value\tacc\tComment\n")


@contextlib.contextmanager
def _hang_guard() -> Iterator[None]:
    def fire(signum, frame):
        raise AssertionError(f"no answer within {HANG_GUARD_S} s")

    previous = signal.signal(signal.SIGALRM, fire)
    signal.alarm(HANG_GUARD_S)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def _expect_one_line_exit_2(kind: str, files: dict[str, bytes | str],
                            argv: Callable[[Path], list[str]]) -> None:
    """Write ``files`` into a fresh folder, run ``main(argv(folder))``; check the outcome."""
    with tempfile.TemporaryDirectory() as name:
        d = Path(name)
        for fname, content in files.items():
            (d / fname).write_bytes(content if isinstance(content, bytes) else content.encode())
        before = sorted(os.listdir(d))
        err = io.StringIO()
        out = io.StringIO()
        with _hang_guard(), contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            rc = main(argv(d))
        lines = err.getvalue().splitlines()
        assert rc == 2, (kind, rc, err.getvalue())
        assert len(lines) == 1 and lines[0].startswith("rattle-lab: error: "), (kind, lines)
        assert out.getvalue() == "", kind
        assert sorted(os.listdir(d)) == before, (kind, "left behind")
    TRIED[kind] = TRIED.get(kind, 0) + 1


def _ingest(*inputs: str, mapping: str | None = None) -> Callable[[Path], list[str]]:
    def argv(d: Path) -> list[str]:
        args = ["ingest", *[str(d / i) for i in inputs], "-o", str(d / "store.h5"), "--quiet"]
        return args + (["--mapping", str(d / mapping)] if mapping else [])
    return argv


FUZZ = settings(max_examples=20, deadline=None, derandomize=True,
                suppress_health_check=[HealthCheck.too_slow])


# --- hypothesis-made ----------------------------------------------------------------------------

@FUZZ
@given(st.floats(0.0, 0.999))
def test_fuzz_hdf5_cut_short(fraction):
    data = _REC.read_bytes()
    _expect_one_line_exit_2("hdf5", {"in.h5": data[:int(len(data) * fraction)]}, _ingest("in.h5"))


@FUZZ
@given(st.integers(0, 43), st.binary(max_size=64))
def test_fuzz_wav_header_cut_or_garbage(cut, tail):
    head = _WAV.read_bytes()[:cut]
    _expect_one_line_exit_2("wav", {"in.wav": b"RIFF" + head[4:] + tail if cut >= 4 else
                                    b"RIFF\x00\x00\x00\x00WAVE" + tail}, _ingest("in.wav"))


@FUZZ
@given(st.lists(st.integers(1, 10**9), min_size=1, max_size=3),
       st.sampled_from(["<f4", "<f8", "<i2", "|u1", "<c16"]), st.binary(max_size=256))
def test_fuzz_npy_declared_shape_lies(shape, dtype, body):
    need = int(np.prod(shape)) * np.dtype(dtype).itemsize
    if len(body) >= need:  # only lies: the bytes must not hold the declared array
        body = body[: need - 1]
    header = repr({"descr": dtype, "fortran_order": False, "shape": tuple(shape)}).encode()
    header += b" " * (63 - (len(header) + 10) % 64) + b"\n"
    npy = b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header + body
    mapping = _LVM_MAPPING.replace('source = "acc"', 'source = "0"')
    _expect_one_line_exit_2("npy", {"in.npy": npy, "map.toml": mapping},
                            _ingest("in.npy", mapping="map.toml"))


@FUZZ
@given(st.integers(5, 10**12), st.lists(st.floats(allow_nan=False, allow_infinity=False),
                                        max_size=4))
def test_fuzz_lvm_declared_samples_lie(n_declared, values):
    rows = "".join(f"{i * 0.0005:.4f}\t{v!r}\n" for i, v in enumerate(values))
    lvm = _LVM_HEAD.format(n=n_declared) + rows
    _expect_one_line_exit_2("lvm", {"in.lvm": lvm, "map.toml": _LVM_MAPPING},
                            _ingest("in.lvm", mapping="map.toml"))


@FUZZ
@given(st.binary(min_size=0, max_size=200))
def test_fuzz_tdms_garbage_after_the_lead_in(body):
    _expect_one_line_exit_2("tdms", {"in.tdms": b"TDSm" + body}, _ingest("in.tdms"))


_KEY = st.text(alphabet="abcdefghijklmnopqrstuvwxyz_", min_size=1, max_size=12)
_VALUE = st.one_of(st.integers(-10**6, 10**6), st.text(max_size=12), st.booleans(),
                   st.floats(allow_nan=False, allow_infinity=False))


def _toml(table: dict[str, dict[str, object]]) -> str:
    out = []
    for name, body in table.items():
        out.append(f"[{name}]")
        for k, v in body.items():
            if isinstance(v, bool):
                out.append(f"{k} = {'true' if v else 'false'}")
            elif isinstance(v, str):
                out.append(f"{k} = {v!r}".replace("\\", "\\\\") if "'" not in v else f"{k} = 1")
            else:
                out.append(f"{k} = {v!r}")
    return "\n".join(out) + "\n"


@FUZZ
@given(st.dictionaries(_KEY.map(lambda k: "x" + k), _VALUE, min_size=1, max_size=4))
def test_fuzz_mapping_toml_with_unknown_keys(extra):
    # a valid mapping plus keys it does not know (each name starts with "x": never a real key)
    body = _LVM_MAPPING.replace("[campaign]\n", "[campaign]\n" + "".join(
        f"{k} = {v!r}\n" if not isinstance(v, (bool, str)) else f"{k} = 1\n"
        for k, v in extra.items()))
    lvm = _LVM_HEAD.format(n=3) + "0\t1.5\n0.0005\t-2.0\n0.001\t0.25\n"
    _expect_one_line_exit_2("mapping_toml", {"in.lvm": lvm, "map.toml": body},
                            _ingest("in.lvm", mapping="map.toml"))


@FUZZ
@given(st.dictionaries(_KEY.map(lambda k: "x" + k), st.dictionaries(_KEY, _VALUE, max_size=3),
                       min_size=1, max_size=3))
def test_fuzz_scene_toml_with_unknown_tables(tables):
    _expect_one_line_exit_2("scene_toml", {"scene.toml": _toml(tables)},
                            lambda d: ["simulate", str(d / "scene.toml"), "-o",
                                       str(d / "out.h5")])


@FUZZ
@given(st.dictionaries(_KEY.map(lambda k: "x" + k), _VALUE, min_size=1, max_size=3),
       st.sampled_from(["pipeline", "ingest", "detect", "fit", "report", "simulate"]))
def test_fuzz_pipeline_toml_with_unknown_keys(keys, table):
    text = _toml({table: keys}) if table != "pipeline" else _toml({"pipeline": keys})
    _expect_one_line_exit_2("pipeline_toml", {"p.toml": text, "rec.h5": _REC.read_bytes()},
                            lambda d: ["run", str(d / "p.toml"), str(d / "rec.h5"), "--out",
                                       str(d / "build"), "--quiet"])


# --- hand-made hostile inputs ---------------------------------------------------------------------

def _edited_record(edit: Callable[[h5py.File, Path], None]) -> dict[str, bytes]:
    with tempfile.TemporaryDirectory() as name:
        d = Path(name)
        src = write_record(d / "in.h5", make_record(n=1024))
        with h5py.File(src, "a") as fh:
            edit(fh, d)
        files = {p.name: p.read_bytes() for p in d.iterdir() if p.is_file()}
    return files


def _external_link(fh: h5py.File, d: Path) -> None:
    del fh[MIC]
    fh[MIC] = h5py.ExternalLink("/etc/hostname", "/x")


def _vds_outside(fh: h5py.File, d: Path) -> None:
    attrs = dict(fh[MIC].attrs)
    del fh[MIC]
    layout = h5py.VirtualLayout(shape=(1024,), dtype="f4")
    layout[:] = h5py.VirtualSource("/tmp/elsewhere.h5", "d", shape=(1024,))
    fh.create_virtual_dataset(MIC, layout, fillvalue=0.0).attrs.update(attrs)


def _external_storage(fh: h5py.File, d: Path) -> None:
    attrs = dict(fh[MIC].attrs)
    del fh[MIC]
    fh.create_dataset(MIC, shape=(1024,), dtype="f4",
                      external=[("/etc/passwd", 0, 4096)]).attrs.update(attrs)


def _huge_chunked(fh: h5py.File, d: Path) -> None:
    attrs = dict(fh[MIC].attrs)
    del fh[MIC]
    fh.create_dataset(MIC, shape=(10**12,), dtype="f4", chunks=(1 << 14,)).attrs.update(attrs)


def _soft_link_loop(fh: h5py.File, d: Path) -> None:
    del fh[MIC]
    fh[MIC] = h5py.SoftLink("/runs/dwell_094/channels/nowhere")


def _deep_groups(fh: h5py.File, d: Path) -> None:
    g = fh["runs/dwell_094"]
    for i in range(20):
        g = g.create_group(f"x_{i}")


HAND_MADE: dict[str, tuple[dict[str, bytes | str], Callable[[Path], list[str]]]] = {
    "hdf5_external_link_to_etc": (_edited_record(_external_link), _ingest("in.h5")),
    "hdf5_virtual_dataset_outside": (_edited_record(_vds_outside), _ingest("in.h5")),
    "hdf5_external_storage_etc_passwd": (_edited_record(_external_storage), _ingest("in.h5")),
    "hdf5_1e12_samples_chunked": (_edited_record(_huge_chunked), _ingest("in.h5")),
    "hdf5_dangling_soft_link": (_edited_record(_soft_link_loop), _ingest("in.h5")),
    "hdf5_nested_20_deep": (_edited_record(_deep_groups), _ingest("in.h5")),
    "lvm_1e12_samples": ({"in.lvm": _LVM_HEAD.format(n=10**12) + "0\t1\n",
                          "map.toml": _LVM_MAPPING}, _ingest("in.lvm", mapping="map.toml")),
    "npy_1e12_shape": ({"in.npy": b"\x93NUMPY\x01\x00v\x00" + (
        b"{'descr': '<f8', 'fortran_order': False, 'shape': (1000000000000,), }"
        .ljust(117) + b"\n"), "map.toml": _LVM_MAPPING.replace('"acc"\nquantity', '"0"\nquantity')},
        _ingest("in.npy", mapping="map.toml")),
    "wav_data_chunk_claims_2gb": ({"in.wav": b"RIFF\xff\xff\xff\x7fWAVEfmt \x10\x00\x00\x00"
                                   b"\x01\x00\x01\x00\x80\xbb\x00\x00\x00w\x01\x00\x02\x00\x10\x00"
                                   b"data\xff\xff\xff\x7f\x00\x01"}, _ingest("in.wav")),
    "tdms_empty_lead_in": ({"in.tdms": b"TDSm"}, _ingest("in.tdms")),
    "mapping_binary": ({"in.lvm": _LVM_HEAD.format(n=1) + "0\t1\n", "map.toml": b"\xff\xfe\x00"},
                       _ingest("in.lvm", mapping="map.toml")),
    "mapping_empty": ({"in.lvm": _LVM_HEAD.format(n=1) + "0\t1\n", "map.toml": ""},
                      _ingest("in.lvm", mapping="map.toml")),
    "scene_negative_gap": ({"s.toml": "[scene]\ngap_m = -1\n"},
                           lambda d: ["simulate", str(d / "s.toml"), "-o", str(d / "o.h5")]),
    "scene_binary": ({"s.toml": b"\x00\x01\x02"},
                     lambda d: ["simulate", str(d / "s.toml"), "-o", str(d / "o.h5")]),
    "pipeline_unknown_output": ({"p.toml": '[pipeline]\noutputs = ["everything"]\n'},
                                lambda d: ["run", str(d / "p.toml"), "default", "--out",
                                           str(d / "b")]),
    "pipeline_not_toml": ({"p.toml": "[[[["},
                          lambda d: ["run", str(d / "p.toml"), "default", "--out", str(d / "b")]),
    "store_is_a_record": ({"rec.h5": _REC.read_bytes(), "in.h5": _REC.read_bytes()},
                          lambda d: ["fit", str(d / "rec.h5"), "--quiet"]),
    "verify_not_a_store": ({"x.h5": b"not hdf5"}, lambda d: ["verify", str(d / "x.h5")]),
}


@pytest.mark.parametrize("name", sorted(HAND_MADE))
def test_hand_made_hostile_input(name):
    files, argv = HAND_MADE[name]
    _expect_one_line_exit_2(name.split("_")[0], files, argv)


def test_a_few_hostile_inputs_through_the_installed_entry_point(tmp_path):
    for name in ("hdf5_external_link_to_etc", "hdf5_1e12_samples_chunked", "lvm_1e12_samples",
                 "wav_data_chunk_claims_2gb"):
        files, argv = HAND_MADE[name]
        d = tmp_path / name
        d.mkdir()
        for fname, content in files.items():
            (d / fname).write_bytes(content if isinstance(content, bytes) else content.encode())
        before = sorted(os.listdir(d))
        proc = run_cli(*argv(d)[0:])
        assert proc.returncode == 2, (name, proc.stderr)
        assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr, proc.stderr
        assert sorted(os.listdir(d)) == before
