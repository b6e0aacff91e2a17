"""scripts/probe_reliability.py (issue 33's probe matrix): its judge and its runners on tiny synthetic inputs
(a bad number refused, a run that is not an error, a server case), and its ``--quick`` CLI cases against a
finished pipeline run when one is there (``VIDSTYLE_PROBE_PIPELINE`` or pipelines/kickboxing with out/)."""

from __future__ import annotations

import importlib.util
import json
import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
spec = importlib.util.spec_from_file_location("probe_reliability", ROOT / "scripts" / "probe_reliability.py")
probe = importlib.util.module_from_spec(spec)
sys.modules["probe_reliability"] = probe
spec.loader.exec_module(probe)


def _in_small_process(code: str, tmp_path: Path) -> dict:
    """Run ``code`` (which sets ``out``, a JSON-able dict) in a fresh interpreter with the probe imported:
    a child's peak RSS (``wait4``'s ``ru_maxrss``) counts the image it was forked from, and a pytest worker
    is large, whereas the probe runs as a small script of its own."""
    import subprocess

    prog = ("import importlib.util, json, sys\n"
            f"spec = importlib.util.spec_from_file_location('probe_reliability', {str(ROOT / 'scripts' / 'probe_reliability.py')!r})\n"
            "probe = importlib.util.module_from_spec(spec); sys.modules['probe_reliability'] = probe\n"
            "spec.loader.exec_module(probe)\n"
            "from pathlib import Path\n"
            f"tmp_path = Path({str(tmp_path)!r})\n" + code + "\nprint(json.dumps(out, default=str))\n")
    p = subprocess.run([sys.executable, "-c", prog], capture_output=True, text=True, check=True, cwd=ROOT)
    return json.loads(p.stdout.strip().splitlines()[-1])


def test_a_refused_bad_number_is_clean_and_a_run_that_works_is_not(tmp_path):
    code = """
import dataclasses
bad = probe.CliCase("match-pose --views 100000", 1,
                    ["match-pose", str(tmp_path / "no.json"), "-l", str(tmp_path / "nolib"), "-o", "{d}/m.json",
                     "--views", "100000"], "--views", "8 GB", ["m.json"])
fine = probe.CliCase("--version", 1, ["--version"], "--views", "", [])
wrote = probe.CliCase("mocap info", 7, ["demo", "make-library", "-o", "{d}/lib", "--performers", "1",
                                        "--action-seconds", "2", "--jobs", "1"], None, "", ["lib"])
out = {"bad": dataclasses.asdict(probe.run_cli_case(bad, tmp_path / "work", timeout=60)),
       "fine": dataclasses.asdict(probe.run_cli_case(fine, tmp_path / "work", timeout=60)),
       "wrote": dataclasses.asdict(probe.run_cli_case(wrote, tmp_path / "work", timeout=120))}
"""
    res = _in_small_process(code, tmp_path)
    r = res["bad"]
    assert r["clean"], r
    assert r["result"] == "exit 2" and r["detail"].startswith("vidstyle: error: --views") and r["file_state"] == "output absent"
    assert 0 < r["seconds"] < 60 and 10 < r["peak_mb"] < 1024
    # exit 0 (and an error line that does not name the flag) is not clean: the judge is not vacuous
    r = res["fine"]
    assert not r["clean"] and "exit 0" in r["detail"]
    # an output written is not clean either
    r = res["wrote"]
    assert not r["clean"] and "output written" in r["detail"] and r["file_state"].startswith("written: lib")


def test_a_timeout_is_reported_and_the_child_killed(tmp_path):
    r = probe.run_measured([sys.executable, "-c", "import time; time.sleep(30)"], tmp_path, timeout=0.5)
    assert r["code"] == "timeout" and r["seconds"] < 5


def test_the_address_space_limit_applies_to_the_child(tmp_path):
    code = """
probe.LIMIT_BYTES = 512 << 20
out = probe.run_measured([sys.executable, "-c", "b = bytearray(1 << 30)"], tmp_path, timeout=30)
"""
    r = _in_small_process(code, tmp_path)
    assert r["code"] == 1 and "MemoryError" in r["stderr"] and r["peak_mb"] < 512


def test_server_case_on_a_tiny_video(tmp_path):
    sys.path.insert(0, str(ROOT / "tests"))
    from annotate_util import numbered_video

    video = numbered_video(tmp_path / "v.mp4", 12)
    d = tmp_path / "srv"
    d.mkdir()
    with probe.Server([video], d / "ann.json", d) as srv:
        assert srv.token
        state = probe._listing(d)
        bad = probe.http_result("frame ²", 5, srv, lambda c: c.get("/api/videos/0/frames/%C2%B2"), "400", "500", d,
                                state)
        good = probe.http_result("frame 3", 5, srv, lambda c: c.get("/api/videos/0/frames/3"), "400", "", d, state)
    assert bad.clean and bad.result == "HTTP 400" and bad.peak_mb > 10
    assert not good.clean and good.result == "HTTP 200"
    text = probe.table([bad, good])
    assert "| **5. The annotation server** |" in text and "1 of 2 cases clean." in text


def _pipeline() -> Path | None:
    p = Path(os.environ.get("VIDSTYLE_PROBE_PIPELINE", ROOT / "pipelines" / "kickboxing"))
    return p if (p / "out" / "augmg" / "library").is_dir() and (p / "out" / "dataset").is_dir() else None


@pytest.mark.slow  # ~20 CLI start-ups (about 20 s)
def test_quick_cli_cases_against_a_finished_pipeline(tmp_path):
    pipeline = _pipeline()
    if pipeline is None:
        pytest.skip("no finished pipeline run (make demo, or set VIDSTYLE_PROBE_PIPELINE)")
    out = tmp_path / "probe.json"
    code = probe.main(["--pipeline", str(pipeline), "--quick", "--only", "cli", "--out", str(out)])
    doc = json.loads(out.read_text())
    bad = [c for c in doc["cases"] if not c["clean"]]
    assert code == 0 and not bad, bad
    assert {c["item"] for c in doc["cases"]} == {1, 4, 7} and len(doc["cases"]) >= 20
