"""Two decompose commands into one folder at once: the one that finishes second puts nothing in
place and says so. Before, both said they had written their files, and the folder held one
run's decomposition.npz and source.npz beside the other's level files (a scan technician's
review: 6 times out of 6)."""
import numpy as np

import pointscale as ps
import pointscale.cli.commands as commands
from pointscale import cli, io


def test_a_decomposition_written_meanwhile_is_not_mixed_with_this_runs_files(tmp_path, monkeypatch, capsys):
    io.write(tmp_path / "in.ply", io.Scan(points=ps.shapes.bumpy_sphere(4000)))
    out = tmp_path / "out"
    other = {"decomposition.npz": b"the other run's model", "level_0.ply": b"the other run's level 0"}
    real = commands.decompose

    def finishing_meanwhile(*args, **kwargs):
        dec = real(*args, **kwargs)
        out.mkdir(exist_ok=True)
        for name, text in other.items():
            (out / name).write_bytes(text)
        return dec

    monkeypatch.setattr(commands, "decompose", finishing_meanwhile)
    assert cli.main(["decompose", str(tmp_path / "in.ply"), "-o", str(out), "--levels", "3"]) == 2
    assert "another command wrote a decomposition into" in capsys.readouterr().err
    assert sorted(p.name for p in out.iterdir()) == sorted(other)  # nothing of this run, no .part files
    assert all((out / name).read_bytes() == text for name, text in other.items())
    # and run again with --force, it replaces the other run's files
    monkeypatch.setattr(commands, "decompose", real)
    assert cli.main(["decompose", str(tmp_path / "in.ply"), "-o", str(out), "--levels", "3", "--force"]) == 0
    assert np.array_equal(io.read(out / "level_2.ply").points, io.read(tmp_path / "in.ply").points)
