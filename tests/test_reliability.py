"""Fault injection: corrupted, truncated and killed files, a full disk, bad paths and configs.

Every test here failed (or hung) before the fix it covers (issue 14, items 3, 4,
8, 9, 10, 11, 14, 15). The damaged files are made by overwriting bytes at
addresses HDF5 itself reports (an object header, a data chunk, a coordinate),
so each test hits the structure it names. Cost: ~15 s in all, most of it one
130-value reference sweep and two CLI subprocesses.
"""

import os
import resource
import shutil
import subprocess
import sys
import textwrap
import warnings

import h5py
import numpy as np
import pytest

import stickslip_fast as ssf
from stickslip_fast.analysis.sweep import load_sweep, sweep
from stickslip_fast.cli import main
from stickslip_fast.cli.config import ConfigError, load_config
from stickslip_fast.io import ConfigMismatchError, ResultFileError, SweepFile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ASYM = ssf.System.preset("asymmetric")
# 130 values: three HDF5 chunks (64 values each) per dataset, so damage to one
# chunk leaves the others to recover
ETAS = np.linspace(2.0, 9.0, 130)
KW = dict(t_end=300.0, t_transient=200.0, max_points=8)
FIELDS = ("points", "t_points", "count", "period", "status_code", "n_steps", "n_rejected",
          "n_crossings", "final_state")  # fmt: skip


def _same(a, b):
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)


def _run(path, **kw):
    """The reference sweep, into ``path``; returns (result, warnings other than no-orbit)."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = sweep(ASYM, "eta", ETAS, out=path, chunk_size=16, progress=False, **KW, **kw)
    return res, [str(w.message) for w in caught if "gave no orbit" not in str(w.message)]


@pytest.fixture(scope="module")
def ref_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("ref") / "ref.h5"
    res, _ = _run(path)
    return path, load_sweep(path)


def _copy(ref_file, tmp_path, name="f.h5"):
    dst = tmp_path / name
    shutil.copy(ref_file[0], dst)
    return dst


def _overwrite(path, offset, data):
    with open(path, "r+b") as fh:
        fh.seek(offset)
        fh.write(data)


def _cli(*args):
    """Run the console entry point in a subprocess with a hang guard."""
    return subprocess.run(
        [sys.executable, "-m", "stickslip_fast.cli", *map(str, args)],
        capture_output=True, text=True, timeout=120, cwd=ROOT,
        env={**os.environ, "PYTHONPATH": ROOT},
    )  # fmt: skip


def _no_leftovers(path):
    for suffix in (".lock", ".partial", ".recovering"):
        assert not os.path.exists(str(path) + suffix), suffix


# ------------------------------------------------------- item 4: bounded opens
def test_corrupted_object_header_fails_fast_instead_of_hanging(ref_file, tmp_path):
    """HDF5's SWMR reader retried a bad metadata checksum 100 times with a doubling
    sleep (2**100 ns): load_sweep, info and resume slept for ever."""
    path = _copy(ref_file, tmp_path)
    with h5py.File(path, "r") as h5:
        addr = h5py.h5o.get_info(h5["points"].id).addr
    _overwrite(path, addr + 40, b"\xa5" * 16)
    script = f"from stickslip_fast.analysis.sweep import load_sweep; load_sweep({str(path)!r})"
    proc = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=60,
        env={**os.environ, "PYTHONPATH": ROOT},
    )  # fmt: skip
    assert proc.returncode != 0
    assert "ResultFileError" in proc.stderr and "'points' cannot be read" in proc.stderr
    info = _cli("info", path)
    assert info.returncode == 2
    assert "corrupted" in info.stderr and "'points'" in info.stderr
    # resume: nothing of 'points' is readable, so every value is computed again
    res, warned = _run(path)
    _same(ref_file[1], res)
    assert any("130 of 130 value(s) could not be read" in w for w in warned)
    _no_leftovers(path)


def test_truncated_file_is_named_and_resumes(ref_file, tmp_path):
    path = _copy(ref_file, tmp_path)
    size = path.stat().st_size
    with open(path, "r+b") as fh:
        fh.truncate(int(size * 0.8))
    with pytest.raises(ResultFileError, match=r"f\.h5: truncated: \d+ bytes on disk"):
        load_sweep(path)
    info = _cli("info", path)
    assert info.returncode == 2 and "truncated" in info.stderr
    assert len(info.stderr.strip().splitlines()) == 1 and "Traceback" not in info.stderr
    _no_leftovers(path)
    res, warned = _run(path)
    _same(ref_file[1], res)
    assert any("truncated" in w and "computed again" in w for w in warned), warned
    _no_leftovers(path)


def test_file_truncated_to_8_kib_is_refused_with_a_reason(ref_file, tmp_path):
    path = _copy(ref_file, tmp_path)
    with open(path, "r+b") as fh:
        fh.truncate(8192)
    with pytest.raises(ResultFileError, match="configuration cannot be read.*truncated"):
        _run(path)
    _no_leftovers(path)
    info = _cli("info", path)
    assert info.returncode == 2 and "truncated" in info.stderr


# ------------------------------------------------------- item 8: checksums
def test_corrupted_data_chunk_is_detected_and_recomputed(ref_file, tmp_path):
    path = _copy(ref_file, tmp_path)
    with h5py.File(path, "r") as h5:
        assert h5["points"].fletcher32 and h5["done"].fletcher32
        chunk = h5["points"].id.get_chunk_info_by_coord((64, 0, 0))  # values 64..127
    _overwrite(path, chunk.byte_offset + chunk.size // 2, b"\xff" * 64)
    with pytest.raises(ResultFileError, match="'points' cannot be read"):
        load_sweep(path)
    info = _cli("info", path)
    assert info.returncode == 2
    assert "points (1 of 3)" in info.stderr and "64 of 130 values affected" in info.stderr
    res, warned = _run(path)
    # only the damaged chunk's 64 values were computed again; the rest was copied
    assert any("64 of 130 value(s) could not be read" in w for w in warned), warned
    _same(ref_file[1], res)
    assert _cli("info", path).returncode == 0


def test_corrupted_coordinate_fails_its_sha256(ref_file, tmp_path):
    path = _copy(ref_file, tmp_path)
    with h5py.File(path, "r") as h5:
        offset = h5["eta"].id.get_offset()
    _overwrite(path, offset + 8 * 5, np.float64(2.5).tobytes())
    with pytest.raises(ResultFileError, match="'eta' do not match their SHA-256"):
        load_sweep(path)
    assert _cli("info", path).returncode == 2
    res, warned = _run(path)  # the values come from the caller, whose SHA-256 matches
    assert any("SHA-256" in w for w in warned)
    np.testing.assert_array_equal(load_sweep(path).values, ETAS)
    _same(ref_file[1], res)


def test_edited_configuration_fails_its_sha256(ref_file, tmp_path):
    path = _copy(ref_file, tmp_path)
    with h5py.File(path, "r+") as h5:  # an edit behind the package's back
        h5.attrs["config"] = h5.attrs["config"].replace('"mode":"restart"', '"mode":"continuation"')
    with pytest.raises(ResultFileError, match="configuration does not match its SHA-256"):
        load_sweep(path)
    assert _cli("info", path).returncode == 2
    res, warned = _run(path)  # resume restores the caller's configuration
    assert any("does not match its SHA-256" in w for w in warned), warned
    _same(ref_file[1], res)
    assert load_sweep(path).mode == "restart"


def _mark_killed(path, undone=slice(100, 130)):
    """Leave ``path`` as a SIGKILLed SWMR writer does: flagged open, some values not done."""
    script = textwrap.dedent(
        f"""
        import os, h5py
        f = h5py.File({str(path)!r}, "r+", libver="latest")
        f.swmr_mode = True
        f["done"][{undone.start}:{undone.stop}] = 0
        f.flush()
        os._exit(0)
        """
    )
    subprocess.run([sys.executable, "-c", script], check=True, timeout=60)


def test_killed_then_truncated_file_recovers_what_it_can(ref_file, tmp_path):
    path = _copy(ref_file, tmp_path)
    _mark_killed(path)
    with pytest.raises(OSError, match="already open for write"):
        h5py.File(path, "r")  # what a plain reader sees after a kill
    with open(path, "r+b") as fh:
        fh.truncate(int(path.stat().st_size * 0.85))
    res, warned = _run(path)
    assert any("truncated" in w for w in warned)
    _same(ref_file[1], res)
    with h5py.File(path, "r") as h5:  # rebuilt: a plain reader opens it again
        assert h5["done"][...].all()


# ------------------------------------------------------- item 10: readers
def test_xarray_reads_a_killed_file_with_swmr_driver_kwds(ref_file, tmp_path):
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    path = _copy(ref_file, tmp_path)
    _mark_killed(path)
    ds = xr.open_dataset(
        path, engine="h5netcdf", driver_kwds={"swmr": True, "libver": "latest"}
    )  # the recipe of docs/file-format.md and docs/reliability.md
    np.testing.assert_array_equal(ds["done"].values[:100], 1)
    np.testing.assert_array_equal(ds["done"].values[100:], 0)
    np.testing.assert_array_equal(ds["period"].values, ref_file[1].period)
    ds.close()
    assert load_sweep(path).count.shape == (130,)  # the package's readers need nothing


# ------------------------------------------------------- item 3: full disk
def test_full_disk_stops_cleanly_and_the_file_resumes(ref_file, tmp_path):
    """RLIMIT_FSIZE stands in for a full disk: HDF5 used to half-write a chunk,
    segfault, and leave a file that no longer opened."""
    cfg = tmp_path / "fz.toml"
    cfg.write_text(
        textwrap.dedent(
            """
            [system]
            preset = "asymmetric"
            [integration]
            t_end = 300.0
            t_transient = 200.0
            max_points = 8
            [sweep]
            param = "eta"
            values = { start = 2.0, stop = 9.0, num = 130 }
            chunk_size = 16
            """
        )
    )
    out = tmp_path / "fz.h5"
    limit = 160 * 1024

    def cap():
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit, limit))

    proc = subprocess.run(
        [sys.executable, "-m", "stickslip_fast.cli", "sweep", str(cfg), "-o", str(out), "--quiet"],
        capture_output=True, text=True, timeout=120, cwd=ROOT, preexec_fn=cap,
        env={**os.environ, "PYTHONPATH": ROOT},
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    err = [line for line in proc.stderr.splitlines() if "warning" not in line]
    assert len(err) == 1 and "Traceback" not in proc.stderr
    assert str(out) in err[0] and "no room to grow" in err[0] and "resume" in err[0]
    with h5py.File(out, "r") as h5:  # closed cleanly: a plain reader opens it
        n_done = int(h5["done"][...].sum())
    assert 0 < n_done < 130, n_done  # finished values were kept
    _no_leftovers(out)
    again = _cli("sweep", cfg, "-o", out, "--quiet")
    assert again.returncode == 0, again.stderr
    _same(ref_file[1], load_sweep(out))


def test_nearly_full_disk_is_probed_before_writing(ref_file, tmp_path, monkeypatch):
    """Near a full disk the room is taken for real (posix_fallocate); a refusal
    stops the sweep before HDF5 writes anything."""
    import errno
    import types

    path = _copy(ref_file, tmp_path)
    with h5py.File(path, "r+") as h5:
        h5["done"][100:] = 0
    before = path.read_bytes()
    calls = []

    def refuse(fd, offset, length):
        calls.append(length)
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(
        os, "fstatvfs", lambda fd: types.SimpleNamespace(f_bavail=1, f_frsize=2**20)
    )
    monkeypatch.setattr(os, "posix_fallocate", refuse)
    from stickslip_fast.io import DiskFullError

    with pytest.raises(DiskFullError, match=r"no room to grow it by \d+ KiB \(No space left"):
        _run(path)
    assert calls and path.read_bytes() == before  # nothing written, file intact
    _no_leftovers(path)
    monkeypatch.undo()
    _same(ref_file[1], _run(path)[0])


# ------------------------------------------------------- item 11: the lock
def test_writer_lock_covers_symlinks(ref_file, tmp_path):
    path = _copy(ref_file, tmp_path)
    link = tmp_path / "link.h5"
    link.symlink_to(path)
    res = load_sweep(path)
    from stickslip_fast.io import SweepLayout

    layout = SweepLayout(("eta",), (ETAS,), False, 8, res.state_names)
    with h5py.File(path, "r") as h5:
        import json

        config = json.loads(h5.attrs["config"])
    with SweepFile.open(path, config, layout):  # a live writer on the real name
        with pytest.raises(ConfigMismatchError, match="another process is writing"):
            _run(link)
    assert link.is_symlink() and link.resolve() == path.resolve()
    _no_leftovers(path)


# ------------------------------------------------------- item 9: OS errors
def test_os_errors_are_one_line_with_exit_2(tmp_path, capsys, monkeypatch):
    sim = sys.modules["stickslip_fast.analysis.simulate"]
    afile = tmp_path / "plain.txt"
    afile.write_text("x")

    def no_compute(*a, **k):
        raise AssertionError("computed before checking the output path")

    monkeypatch.setattr(sim, "simulate", no_compute)
    cfg = tmp_path / "s.toml"
    cfg.write_text('[sweep]\nparam = "eta"\nvalues = [2.0, 3.0]\n')
    cases = [
        (["simulate", str(tmp_path)], str(tmp_path)),  # the config is a directory
        (["simulate", "--t-end", "300", "-o", str(afile / "run.h5")], "plain.txt"),
        (["simulate", "--t-end", "300", "--save", str(tmp_path / "no" / "x.npz")], "no"),
        (["simulate", "--t-end", "300", "-o", str(tmp_path)], str(tmp_path)),
        (["sweep", str(cfg), "--t-end", "300", "-o", str(afile / "s.h5")], "plain.txt"),
        (["sweep", str(cfg), "--t-end", "300", "-o", str(tmp_path)], str(tmp_path)),
    ]
    for argv, names in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and err.startswith("stickslip-fast: error:"), err
        assert names in err, (argv, err)


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write anywhere")
def test_read_only_directory_is_named(tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    assert main(["simulate", "--t-end", "300", "-o", str(ro / "x.h5")]) == 2
    assert "permission denied" in capsys.readouterr().err


def test_memory_errors_are_one_line_with_the_size(tmp_path, capsys):
    cfg = tmp_path / "big.toml"
    cfg.write_text(
        '[system]\npreset = "asymmetric"\n[integration]\nt_end = 300.0\n'
        '[sweep]\nparam = "eta"\nvalues = { start = 1.0, stop = 2.0, num = 1000000000000 }\n'
    )
    assert main(["sweep", str(cfg), "-o", str(tmp_path / "big.h5")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "out of memory" in err and "TiB" in err


# ------------------------------------------------------- item 14: config errors
@pytest.mark.parametrize(
    "content, match",
    [
        (b"\x00\xff\xfe\x01binary", r"c\.toml: not a TOML text file \(invalid UTF-8"),
        (b'system = "asymmetric"\n', r"c\.toml: 'system' must be a table"),
        (
            b'[sweep]\nparam = "eta"\nvalues = { start = "a", stop = 2.0, num = 3 }\n',
            r"c\.toml: \[sweep\]\.values\.start must be a number, got 'a'",
        ),
        (b"integration = 3\n", r"c\.toml: 'integration' must be a table"),
        (
            b'[sweep]\nparam = "bogus"\nvalues = [1.0]\n',
            r"\[sweep\]\.param 'bogus' cannot be swept",
        ),
        (
            b'[sweep]\nparam = "eta"\nvalues = [2.0]\nmode = "sideways"\n',
            r"\[sweep\]\.mode must be",
        ),
        (b'[initial]\ny0 = "x"\n', r"\[initial\]\.y0: y0 must be an array of 4 numbers"),
    ],
)
def test_config_errors_name_the_file_and_key(tmp_path, content, match):
    path = tmp_path / "c.toml"
    path.write_bytes(content)
    with pytest.raises(ConfigError, match=match):
        load_config(path)


def test_config_that_is_a_directory_is_named(tmp_path):
    with pytest.raises(ConfigError, match="is a directory, not a TOML config file"):
        load_config(tmp_path)


# ------------------------------------------------------- item 15: info
def test_info_describes_a_trajectory_file(tmp_path, capsys):
    out = tmp_path / "run.h5"
    assert main(["simulate", "--t-end", "300", "--t-transient", "100", "--sample-dt", "1",
                 "-o", str(out), "--show", "0"]) == 0  # fmt: skip
    capsys.readouterr()
    assert main(["info", str(out)]) == 0
    text = capsys.readouterr().out
    one = ssf.simulate(ASYM, 300.0, 100.0, sample_dt=1.0)  # what the file should describe
    period = one.period if one.period else "none detected"
    assert "single run" in text and f"status {one.status}, period {period}" in text
    assert f"{one.n_steps} steps" in text and f"{len(one.t_poincare)} Poincare points" in text
    assert "201 samples every 1" in text and "x1, dx1, phi1, dphi1" in text


def test_an_error_caused_by_ctrl_c_exits_130_as_interrupted(tmp_path, capsys, monkeypatch):
    # Ctrl-C inside Numba's compiler can leave it half done, and the error that follows
    # (a RuntimeError from its cache, seen on a cold CLI simulate) has the
    # KeyboardInterrupt in its context: that is an interruption (130), not a crash (1)
    from stickslip_fast.cli import commands

    def interrupted_compile(args):
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt:
            raise RuntimeError("no compiled object yet for <Library 'w_solve'>")  # noqa: B904

    def plain_bug(args):
        raise RuntimeError("a bug")

    def bad_value(args):
        try:
            raise KeyError("eta")
        except KeyError as exc:
            raise ValueError("bad field 'eta'") from exc

    monkeypatch.setattr(commands, "_cmd_simulate", interrupted_compile)
    assert main(["simulate", "--t-end", "300"]) == 130
    assert capsys.readouterr().err.strip() == "stickslip-fast: interrupted"
    monkeypatch.setattr(commands, "_cmd_simulate", plain_bug)
    with pytest.raises(RuntimeError, match="a bug"):
        main(["simulate", "--t-end", "300"])
    monkeypatch.setattr(commands, "_cmd_simulate", bad_value)
    assert main(["simulate", "--t-end", "300"]) == 2
    assert "bad field 'eta'" in capsys.readouterr().err
