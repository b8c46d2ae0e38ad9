"""scripts/output_fingerprints.py: --compare's report and exit codes on hand-made files, and one
small case run twice giving the same fingerprints."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

SCRIPT = Path(__file__).resolve().parents[1] / "scripts" / "output_fingerprints.py"


def script(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *args], capture_output=True, text=True)


def fingerprints(path: Path, entries: dict, arrays=None) -> Path:
    meta = {"threads": 2, "quick": True, "arrays": str(arrays) if arrays else None}
    path.write_text(json.dumps({"meta": meta, "inputs": {"shape": {"points": 4, "diagonal": 2.0}},
                                "entries": entries}))
    return path


def test_compare_lists_what_differs_and_exits_1(tmp_path):
    same = {"dtype": "<f8", "shape": [4], "sha256": "aa"}
    report = {"json": '{"count": 3}', "sha256": "bb"}
    a = fingerprints(tmp_path / "a.json", {"shape/input": same, "shape/x": same, "shape/report": report})
    assert script("--compare", str(a), str(a)).returncode == 0

    # x differs (its arrays were kept), the report differs, and each file has an entry of its own.
    for name, x in (("a", [0.0, 1.0, 2.0, 3.0]), ("b", [0.0, 1.0, 2.0, 3.5])):
        (tmp_path / name / "shape").mkdir(parents=True)
        np.save(tmp_path / name / "shape" / "x.npy", np.array(x))
    a = fingerprints(tmp_path / "a.json", {"shape/input": same, "shape/x": same, "shape/report": report,
                                           "shape/gone": same}, tmp_path / "a")
    b = fingerprints(tmp_path / "b.json", {"shape/input": same, "shape/x": {**same, "sha256": "cc"},
                                           "shape/report": {"json": '{"count": 4}', "sha256": "dd"},
                                           "shape/new": same}, tmp_path / "b")
    result = script("--compare", str(a), str(b))
    assert result.returncode == 1, result.stdout + result.stderr
    out = result.stdout
    assert "differs: shape/x (<f8 [4]): 1 of 4 values, largest difference 0.5 = 0.25 of the diagonal" in out
    assert 'differs: shape/report: {"count": 3} against {"count": 4}' in out
    assert f"only in {a}: shape/gone" in out and f"only in {b}: shape/new" in out
    assert "1 entries identical, 2 differ, 2 in one file only" in out


def test_a_case_run_twice_gives_the_same_fingerprints(tmp_path):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    for path in (a, b):
        result = script("--out", str(path), "--quick", "--only", "handles")
        assert result.returncode == 0, result.stdout + result.stderr
    entries = json.loads(a.read_text())["entries"]
    assert "handles/decompose/to_dict/details" in entries and "handles/reconstruct/folds_prevent/limiter" in entries
    result = script("--compare", str(a), str(b))
    assert result.returncode == 0, result.stdout
