"""Files are written whole or not at all; writers emit only what readers take."""

import os

import numpy as np
import pandas as pd
import pytest

from inskit import io
from inskit.errors import InputError
from inskit.files import atomic_write, check_folder_writable
from inskit.types import NavSolution


def _sol(n=5, lon_deg=179.999, dlon_deg=0.01, lat_deg=10.0):
    t = np.arange(n, dtype=float)
    lla = np.column_stack([np.full(n, np.radians(lat_deg)), np.radians(lon_deg + dlon_deg * t), np.zeros(n)])
    return NavSolution.from_euler(t, lla, np.zeros((n, 3)), np.zeros((n, 3)))


@pytest.mark.parametrize("name", ["sol.csv", "sol.parquet"])
def test_interrupted_write_leaves_nothing_under_the_final_name(tmp_path, monkeypatch, name):
    """Ctrl-C while the bytes go out (inside the writers' atomic block)."""
    import pyarrow.csv as pcsv
    import pyarrow.parquet as pq

    path = tmp_path / name

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(pcsv, "write_csv", boom)
    monkeypatch.setattr(pq, "write_table", boom)
    monkeypatch.setattr(pd.DataFrame, "to_csv", boom)
    with pytest.raises(KeyboardInterrupt):
        io.write_solution(path, _sol())
    assert list(tmp_path.iterdir()) == []


def test_failed_write_names_the_file(tmp_path):
    path = tmp_path / "x.txt"
    with pytest.raises(InputError, match="x.txt: could not be written"):
        with atomic_write(path) as tmp:
            tmp.write_text("half")
            raise OSError(28, "No space left on device")
    assert not path.exists() and list(tmp_path.iterdir()) == []


def test_read_only_folder_is_found_before_the_work(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    os.chmod(ro, 0o500)
    try:
        if os.access(ro, os.W_OK):  # root ignores permissions: nothing to test here
            pytest.skip("running as a user who can write anywhere")
        with pytest.raises(InputError, match="not writable"):
            check_folder_writable(ro / "out")
    finally:
        os.chmod(ro, 0o700)


def test_writers_wrap_longitude_across_the_date_line(tmp_path):
    sol = _sol()  # 179.999 .. 180.039 deg
    io.write_solution(tmp_path / "s.csv", sol)
    lon = pd.read_csv(tmp_path / "s.csv")["lon_deg"].to_numpy()
    assert np.all((lon > -180) & (lon <= 180))
    assert lon[0] == pytest.approx(179.999) and lon[-1] == pytest.approx(-179.961)
    back = io.read_solution(tmp_path / "s.csv")
    assert np.allclose(np.cos(back.lla[:, 1]), np.cos(sol.lla[:, 1]))


def test_writer_refuses_an_invalid_latitude(tmp_path):
    sol = _sol(lat_deg=89.9999)
    lla = sol.lla.copy()
    lla[3, 0] = np.radians(90.5)
    bad = NavSolution._trusted(sol.time, lla, sol.v_n, sol.q_nb)
    with pytest.raises(InputError, match="latitude 90.5.*row 3"):
        io.write_solution(tmp_path / "s.csv", bad)
    assert not (tmp_path / "s.csv").exists()


def test_mechanize_refuses_to_overwrite_its_input(tmp_path):
    import subprocess
    import sys

    from inskit.simulation import StationaryTrajectory, ideal_imu

    t = np.arange(0.0, 2.0, 0.01)
    f = tmp_path / "imu.csv"
    io.write_imu(f, ideal_imu(StationaryTrajectory((0.7, 0.1, 10.0)), t, nodes=1))
    before = f.read_bytes()
    p = subprocess.run([sys.executable, "-m", "inskit.cli", "mechanize", str(f), "--init", "40,0,10,0,0,0,0,0,0",
                        "--out", str(f), "--force"], capture_output=True, text=True, timeout=120)
    assert p.returncode == 2 and "is an input of this command" in p.stderr
    assert f.read_bytes() == before


def test_interrupted_figure_leaves_nothing(tmp_path, monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from inskit.files import save_figure

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])

    def boom(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr(fig, "savefig", boom)
    with pytest.raises(KeyboardInterrupt):
        save_figure(fig, tmp_path / "f.png")
    assert list(tmp_path.iterdir()) == []


def test_write_csv_fast_path_keeps_text_columns_and_quotes_when_needed(tmp_path):
    """Numeric and text columns go through the vectorised writer; a text
    value that would need quoting sends the table to pandas, which quotes."""
    import numpy as np
    import pandas as pd

    from inskit.files import write_csv

    p = tmp_path / "a.csv"
    write_csv(p, {"m": np.array(["nhc", "gnss_pos"], dtype=object), "t": np.array([1.5, 2.0]),
                  "k": np.array([1, 0])}, "%.10g")
    assert p.read_text() == "m,t,k\nnhc,1.5,1\ngnss_pos,2,0\n"
    write_csv(p, {"m": np.array(["a,b", "c"], dtype=object), "t": np.array([1.0, 2.0])}, "%.10g")
    back = pd.read_csv(p)
    assert back["m"].tolist() == ["a,b", "c"] and back["t"].tolist() == [1.0, 2.0]


def test_write_csv_parts_writes_the_joined_table(tmp_path):
    """A table given in parts (each written as the writer reaches it) is the
    file of the whole table; no part, the header alone."""
    import numpy as np

    from inskit.files import write_csv_fast, write_csv_parts

    rng = np.random.default_rng(3)
    parts = [{"m": np.full(n, name, dtype=object), "x": rng.normal(size=n) * 1e-3, "k": np.arange(n)}
             for n, name in ((5, "a"), (0, "b"), (7, "c"))]
    write_csv_parts(tmp_path / "p.csv", ["m", "x", "k"], iter(parts), 10)
    write_csv_fast(tmp_path / "w.csv", {c: np.concatenate([q[c] for q in parts]) for c in ("m", "x", "k")}, 10)
    assert (tmp_path / "p.csv").read_bytes() == (tmp_path / "w.csv").read_bytes()
    assert len((tmp_path / "p.csv").read_text().splitlines()) == 13
    write_csv_parts(tmp_path / "e.csv", ["m", "x"], [], 10)
    assert (tmp_path / "e.csv").read_text() == "m,x\n"


def test_write_csv_fast_path_writes_integers_exactly(tmp_path):
    import numpy as np

    from inskit.files import write_csv

    p = tmp_path / "i.csv"
    write_csv(p, {"n": np.array([1234567, 2**53 + 1]), "t": np.array([1.5, 2.0])}, "%.6g")
    assert p.read_text() == "n,t\n1234567,1.5\n9007199254740993,2\n"


def test_require_file_tells_a_folder_from_a_missing_file(tmp_path):
    """[imu] file = "sim" (the simulation's folder) said 'sim: no such file'."""
    from inskit.files import require_file

    (tmp_path / "f.csv").write_text("x\n")
    assert require_file(tmp_path / "f.csv") == tmp_path / "f.csv"
    with pytest.raises(InputError, match=r": no such file$"):
        require_file(tmp_path / "nope.csv")
    for read in (io.read_imu, io.read_gnss, io.read_solution):
        with pytest.raises(InputError, match=rf"{tmp_path.name}: is a folder; expected a file$"):
            read(tmp_path)


def test_an_output_folder_that_is_a_file_or_under_one_is_said_to_be(tmp_path):
    f = tmp_path / "afile"
    f.write_text("mine\n")
    with pytest.raises(InputError, match=r"afile: is a file; expected an output folder$"):
        check_folder_writable(f)
    with pytest.raises(InputError, match=r"afile: is a file; expected an output folder \(so .*afile/a/b cannot be"):
        check_folder_writable(f / "a" / "b")
    assert f.read_text() == "mine\n"


def test_a_folder_that_existed_is_never_taken_for_one_made_here(tmp_path, monkeypatch):
    """'--out x/../E/new' with no x and an empty E: E looked missing (x did not exist) and was removed
    when the command then failed."""
    import pathlib

    from inskit import files

    monkeypatch.chdir(tmp_path)
    (tmp_path / "E").mkdir()
    files._MADE.clear()
    files.check_folder_writable(pathlib.Path("x/../E/new"))
    files.remove_made_folders()
    assert (tmp_path / "E").is_dir() and not (tmp_path / "E" / "new").exists()


def test_staged_files_land_whole_or_leave_the_old_set(tmp_path, monkeypatch):

    from inskit.files import staged_files

    out = tmp_path / "run"
    out.mkdir()
    (out / "a.txt").write_text("old a")
    (out / "b.txt").write_text("old b")
    # a complete set replaces the old one
    with staged_files(out) as stage:
        stage(out / "a.txt").write_text("new a")
        stage(out / "c.txt").write_text("new c")
    assert (out / "a.txt").read_text() == "new a" and (out / "c.txt").read_text() == "new c"
    assert (out / "b.txt").read_text() == "old b"
    assert sorted(p.name for p in out.iterdir()) == ["a.txt", "b.txt", "c.txt"]  # no staging folder left
    # a move that fails midway undoes the ones already made
    real = os.replace

    failed = []

    def failing(src, dst):  # the disk fills as the staged b.txt moves in (once)
        if not failed and os.path.basename(dst) == "b.txt" and os.path.basename(os.path.dirname(src)).startswith(
                ".staging-"):
            failed.append(src)
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(InputError, match="could not be written"):
        with staged_files(out) as stage:
            stage(out / "a.txt").write_text("newer a")
            stage(out / "d.txt").write_text("new d")
            stage(out / "b.txt").write_text("newer b")
    assert (out / "a.txt").read_text() == "new a"  # restored
    assert (out / "b.txt").read_text() == "old b"
    assert not (out / "d.txt").exists()  # the new file of the failed set went
    assert failed and sorted(p.name for p in out.iterdir()) == ["a.txt", "b.txt", "c.txt"]


def test_write_json_is_strict_json_whole_or_nothing(tmp_path, monkeypatch):
    """The result files of reproduce (reproduce.json, schemes.json, bench.json, entries.json, results.json)
    were written by json.dumps' default, which puts NaN and Infinity into the file: not JSON."""
    import json
    from pathlib import Path

    from inskit.files import write_json

    p = write_json(tmp_path / "r.json", {"a": float("nan"), "b": [np.float32(1.5), np.inf, -np.inf],
                                         "c": np.arange(2), 3: np.bool_(True), "d": Path("x/y"), "e": (1, None)})

    def refuse(name):
        raise ValueError(name)

    assert json.loads(p.read_text(), parse_constant=refuse) == {"a": None, "b": [1.5, None, None], "c": [0, 1],
                                                                "3": True, "d": "x/y", "e": [1, None]}
    monkeypatch.setattr(os, "replace", lambda a, b: (_ for _ in ()).throw(KeyboardInterrupt()))
    with pytest.raises(KeyboardInterrupt):
        write_json(tmp_path / "s.json", {"a": 1})
    assert sorted(x.name for x in tmp_path.iterdir()) == ["r.json"]


def test_staged_tree_moves_summary_last_and_names_final_paths(tmp_path, monkeypatch):
    """files.staged_tree (last=): the files a writer put into the staging folder land in the folder, summary.json
    last; a failure leaves the folder as it was, and a writer's message names the file by its final path."""
    from inskit.files import staged_tree

    out = tmp_path / "run"
    out.mkdir()
    (out / "old.txt").write_text("old")
    order = []
    real = os.replace
    monkeypatch.setattr(os, "replace", lambda a, b: (order.append(os.path.basename(b)), real(a, b))[1])
    with staged_tree(out, last=("summary.json",)) as stage:
        for name in ("summary.json", "b.csv", "a.png"):
            (stage / name).write_text(name)
    assert [n for n in order if n != "old.txt"][-1] == "summary.json"
    assert sorted(p.name for p in out.iterdir()) == ["a.png", "b.csv", "old.txt", "summary.json"]
    with pytest.raises(InputError) as e:
        with staged_tree(out, last=("summary.json",)) as stage:
            (stage / "b.csv").write_text("new")
            raise InputError(f"{stage / 'c.csv'}: could not be written (No space left on device)")
    assert str(e.value) == f"{out / 'c.csv'}: could not be written (No space left on device)"
    assert (out / "b.csv").read_text() == "b.csv"
    assert sorted(p.name for p in out.iterdir()) == ["a.png", "b.csv", "old.txt", "summary.json"]


def test_an_output_that_is_a_folder_is_refused_even_with_force(tmp_path):
    """`inskit simulate S --out D --force` with a folder D/scenario.png (the user's, holding files): the set's
    commit moved the folder aside and removed it with the staging folder, and all it held; now refused before
    the work, --force or not."""
    from inskit.files import check_outputs

    (tmp_path / "scenario.png").mkdir()
    (tmp_path / "scenario.png" / "mine.txt").write_text("keep")
    for overwrite in (False, True):
        with pytest.raises(InputError, match=r"scenario.png: is a folder; refusing to replace it by a file"):
            check_outputs([tmp_path / "imu.csv", tmp_path / "scenario.png"], [], overwrite)
    assert (tmp_path / "scenario.png" / "mine.txt").read_text() == "keep"


def test_staged_paths_land_whole_or_leave_the_old_files_in_every_folder(tmp_path, monkeypatch):
    """Files of one set in two folders (a command's --plot and --toml): a rename that fails midway undoes the
    ones made; an error in the block leaves no temporary file."""
    from inskit.files import staged_paths

    a, b = tmp_path / "x" / "a.txt", tmp_path / "y" / "b.txt"
    a.parent.mkdir()
    b.parent.mkdir()
    a.write_text("old a")
    with pytest.raises(RuntimeError):
        with staged_paths() as stage:
            stage(a).write_text("new a")
            raise RuntimeError("the work failed")
    assert a.read_text() == "old a" and sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == ["a.txt"]
    real = os.replace

    def failing(src, dst):  # the disk fills as b.txt moves in
        if os.path.basename(dst) == "b.txt":
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(InputError, match=r"b.txt: could not be written \(No space left on device\)"):
        with staged_paths() as stage:
            stage(a).write_text("new a")
            stage(b).write_text("new b")
    assert a.read_text() == "old a" and not b.exists()
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == ["a.txt"]
    monkeypatch.undo()
    with staged_paths() as stage:
        stage(a).write_text("new a")
        stage(b).write_text("new b")
    assert a.read_text() == "new a" and b.read_text() == "new b"
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == ["a.txt", "b.txt"]


def test_staged_tree_moves_a_whole_tree_or_leaves_the_folder_as_it_was(tmp_path, monkeypatch):
    """A reproduction's figures, tables and subfolders: all moved in at the end, or none; the paths the job
    returns (in the staging folder) relocated to the folder."""
    from inskit.files import check_results_folder, relocated, staged_tree

    out = tmp_path / "out"
    out.mkdir()
    (out / "fig.png").write_text("old fig")
    with pytest.raises(InputError, match=r"out: already holds files; refusing to overwrite them \(use --force"):
        check_results_folder(out)
    assert check_results_folder(out, overwrite=True) == out
    with pytest.raises(RuntimeError):
        with staged_tree(out) as tmp:
            (tmp / "fig.png").write_text("new fig")
            (tmp / "sim").mkdir()
            (tmp / "sim" / "imu.csv").write_text("new imu")
            raise RuntimeError("the job failed")
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == ["fig.png"]
    assert (out / "fig.png").read_text() == "old fig"
    real = os.replace

    def failing(src, dst):  # the disk fills as the second file moves in
        if os.path.basename(dst) == "imu.csv":
            raise OSError(28, "No space left on device")
        return real(src, dst)

    monkeypatch.setattr(os, "replace", failing)
    with pytest.raises(InputError, match="could not be written"):
        with staged_tree(out) as tmp:
            (tmp / "fig.png").write_text("new fig")
            (tmp / "sim").mkdir()
            (tmp / "sim" / "imu.csv").write_text("new imu")
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == ["fig.png"]
    assert (out / "fig.png").read_text() == "old fig"
    monkeypatch.undo()
    with staged_tree(out) as tmp:
        (tmp / "fig.png").write_text("new fig")
        (tmp / "sim").mkdir()
        (tmp / "sim" / "imu.csv").write_text("new imu")
        res = {"figures": [str(tmp / "fig.png")], "sim": tmp / "sim", "note": "kept", "n": 1}
    assert relocated(res, tmp, out) == {"figures": [str(out / "fig.png")], "sim": str(out / "sim"), "note": "kept",
                                        "n": 1}
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == ["fig.png", "sim", "sim/imu.csv"]
    assert (out / "fig.png").read_text() == "new fig"


def test_staged_paths_messages_name_the_final_file(tmp_path):
    """A writer's failure inside the set named its temporary file ('.part-NNN-a.png: could not be written')."""
    from inskit.files import staged_paths, write_text

    with pytest.raises(InputError) as info:
        with staged_paths() as stage:
            write_text(stage(tmp_path / "missing" / "a.txt"), "x")
    assert str(info.value).startswith(f"{tmp_path / 'missing' / 'a.txt'}: could not be written"), info.value
    assert ".part" not in str(info.value)


def test_staged_files_messages_name_the_final_path(tmp_path):
    """A writer's failure inside files.staged_files named the file by its staging path
    (D/.staging-xxxx/imu.csv: could not be written); now by the path the user asked for."""
    from inskit.files import staged_files

    out = tmp_path / "run"
    with pytest.raises(InputError) as e:
        with staged_files(out) as stage:
            raise InputError(f"{stage(out / 'imu.csv')}: could not be written (No space left on device)")
    assert str(e.value) == f"{out / 'imu.csv'}: could not be written (No space left on device)"
    assert not list(out.iterdir())
