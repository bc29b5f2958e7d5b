"""Issue 44 (class 4, part of 8): the Python API and the fleet never write over their inputs or
replace files they did not write; the fleet's LocalCluster listens on 127.0.0.1 only.
The fleet checks run before any Dask import, so they need no Dask installation."""
import json
import subprocess
import sys
import types

import pytest

import semap
from semap import fleet
from conftest import BUILD, skip_or_fail


def tree(folder):
    return {str(p.relative_to(folder)): (p.read_bytes() if p.is_file() and not p.is_symlink() else None)
            for p in sorted(folder.rglob("*"))}


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    semap_exe = BUILD / "semap"
    if not semap_exe.exists():
        skip_or_fail("build/semap not built")
    root = tmp_path_factory.mktemp("outsafe")
    rec = root / "rec"
    subprocess.run([str(semap_exe), "synth", "--out", str(rec), "--frames", "6", "--seed", "3", "--objects", "2",
                    "--width", "160", "--height", "120"], check=True, capture_output=True)
    (rec / "report.json").write_text('{"the recording": "its own report"}\n')
    return rec


def test_run_refuses_the_dataset_or_a_folder_holding_it(recording):
    before = tree(recording.parent)
    for out in (recording, recording / "rgb" / "..", recording.parent):
        with pytest.raises(semap.Error, match="input"):
            semap.run(str(recording), str(out), segmenter="none")
    assert tree(recording.parent) == before


def test_fleet_refuses_an_out_that_is_or_holds_a_recording(recording, capsys):
    before = tree(recording.parent)
    assert fleet.main([str(recording), "--out", str(recording)]) == 1
    assert fleet.main([str(recording), "--out", str(recording.parent)]) == 1
    err = capsys.readouterr().err
    assert err.count("semap.fleet: error:") == 2 and "recording" in err
    assert tree(recording.parent) == before


def test_fleet_keeps_a_fleet_folder_and_fleet_json_it_did_not_write(recording, tmp_path, capsys):
    out = tmp_path / "out"
    (out / ".fleet").mkdir(parents=True)
    (out / ".fleet" / "notes.txt").write_text("mine")
    before = tree(out)
    assert fleet.main([str(recording), "--out", str(out)]) == 1
    assert ".fleet" in capsys.readouterr().err
    assert tree(out) == before
    (out / ".fleet" / "notes.txt").unlink()
    (out / ".fleet").rmdir()
    (out / "fleet.json").write_text('{"mine": true}\n')
    before = tree(out)
    assert fleet.main([str(recording), "--out", str(out)]) == 1
    assert "fleet.json" in capsys.readouterr().err
    assert tree(out) == before
    # What the fleet wrote itself (its key) passes the check.
    (out / "fleet.json").write_text(json.dumps({"semap_fleet": 1, "recordings": []}))
    assert fleet.output_problem(out, [str(recording)]) is None


def test_fleet_local_cluster_and_dashboard_bind_to_localhost(monkeypatch):
    seen = {}

    class LocalCluster:
        def __init__(self, **kwargs):
            seen.update(kwargs)

    fake = types.ModuleType("distributed")
    fake.LocalCluster = LocalCluster
    fake.Client = lambda *args, **kwargs: ("client", args, kwargs)
    monkeypatch.setitem(sys.modules, "distributed", fake)
    fleet.make_client(None, 1)
    assert seen["host"] == "127.0.0.1"
    assert seen["dashboard_address"].startswith("127.0.0.1:")
    client, cluster = fleet.make_client("tcp://10.0.0.5:8786", 1)
    assert cluster is None and client[1] == ("tcp://10.0.0.5:8786",)
