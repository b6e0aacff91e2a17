"""``vidstyle learn-style`` / ``generate`` end to end, and bad input."""

from __future__ import annotations

import itertools
import json

import numpy as np
import pytest

from vidstyle.cli import main
from vidstyle.style.artifact import Style
from vidstyle.style.synthetic import CLASSES, write_fake_dataset


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    root = tmp_path_factory.mktemp("ds")
    write_fake_dataset(root, n_performers=2, n_videos=2, events_per_video=80, seed=3)
    return root


@pytest.fixture(scope="module")
def style_file(dataset, tmp_path_factory):
    out = tmp_path_factory.mktemp("style") / "style.json"
    labels = [str(dataset / "labels" / f"p00_perf{i}.json") for i in range(2)]
    assert main(["learn-style", *labels, "--out", str(out), "--n-init", "2", "--modes", "1-4"]) == 0
    return out


def test_style_file_schema(style_file, dataset):
    doc = json.loads(style_file.read_text())
    assert doc["schema_version"] == 2 and doc["kind"] == "vidstyle.style" and doc["seed"] == 0
    assert doc["action_style"] is None  # schema 2: fitted only with --poses-dir
    assert doc["actions"] == list(CLASSES[:6]) and doc["classes"] == list(CLASSES)
    assert doc["params"]["events"]["ignore"] == ["Guard", "Step"]
    assert doc["performer"] == "p00" and len(doc["sources"]) == 2
    assert doc["n_events"] == sum(s["n_events"] for s in doc["sources"]) == sum(doc["action_counts"].values())
    A, K = 6, doc["model_b"]["n_modes"]
    assert np.asarray(doc["model_a"]["transition"]).shape == (A, A)
    assert np.asarray(doc["model_a"]["emission"]).shape == (A, A)
    assert np.asarray(doc["model_b"]["emission"]).shape == (K, A)
    assert set(doc["model_b"]["selection"]["scores"]) == {"1", "2", "3", "4"}
    for key in ("model_a", "model_b", "bigram"):
        assert np.isfinite(doc[key]["log_likelihood"])
    assert set(doc["durations"]) == set(doc["actions"])
    # the learned chain is much closer to the performer's true chain than a uniform chain is
    truth = np.asarray(json.loads((dataset / "dataset.json").read_text())["performers"][0]["chain"]["transition"])
    mae = np.abs(np.asarray(doc["model_a"]["transition"]) - truth).mean()
    assert mae < 0.5 * np.abs(1 / 6 - truth).mean()
    again = json.loads(json.dumps(Style.load(style_file).to_dict(), default=lambda o: o.tolist()))
    assert again.keys() == doc.keys()
    for key in ("model_a", "model_b", "bigram"):
        for m in ("start", "transition"):
            np.testing.assert_allclose(again[key][m], doc[key][m])
    assert again["durations"] == doc["durations"] and again["params"] == doc["params"]


def test_generate_text_is_deterministic(style_file, capsys):
    args = ["generate", "--style", str(style_file), "--start", "Jab", "--length", "40", "--seed", "1"]
    assert main(args) == 0
    first = capsys.readouterr().out
    assert main(args) == 0
    assert capsys.readouterr().out == first
    words = first.split()
    assert len(words) == 40 and words[0] == "Jab" and set(words) <= set(CLASSES[:6])
    assert main(args[:-1] + ["2"]) == 0
    assert capsys.readouterr().out != first


@pytest.mark.parametrize("model", ["a", "b", "bigram"])
def test_generate_json_and_csv(style_file, tmp_path, model):
    js, cs = tmp_path / "seq.json", tmp_path / "seq.csv"
    base = ["generate", "--style", str(style_file), "--start", "Hook", "--length", "12", "--seed", "4",
            "--model", model]
    assert main(base + ["--format", "json", "--out", str(js)]) == 0
    assert main(base + ["--format", "csv", "--out", str(cs)]) == 0
    doc = json.loads(js.read_text())
    assert doc["seed"] == 4 and doc["start"] == "Hook" and len(doc["events"]) == 12
    ev = doc["events"]
    assert ev[0]["action"] == "Hook" and all(e["duration_frames"] >= 1 for e in ev)
    assert all(b["start_frame"] == a["start_frame"] + a["duration_frames"] for a, b in itertools.pairwise(ev))
    rows = cs.read_text().strip().splitlines()
    assert rows[0] == "index,action,duration_frames,start_frame" and len(rows) == 13
    assert rows[1].split(",")[1:3] == [ev[0]["action"], str(ev[0]["duration_frames"])]


def _label_file(path, labels, classes=CLASSES):
    path.write_text(json.dumps({"fps": 20, "classes": list(classes), "labels": labels}))
    return str(path)


def _fails(capsys, args, out=None, message=None):
    code = main(args)
    err = capsys.readouterr().err
    assert code != 0, err
    assert err.startswith("vidstyle: error:") and err.count("\n") == 1, err
    if message:
        assert message in err, err
    if out is not None:
        assert not out.exists()


def test_bad_generate_input(style_file, tmp_path, capsys):
    out = tmp_path / "o.txt"
    g = ["generate", "--style", str(style_file), "--out", str(out)]
    _fails(capsys, g + ["--start", "Kick"], out, "unknown action 'Kick'")
    _fails(capsys, g + ["--start", "Guard"], out, "ignored filler")
    _fails(capsys, g + ["--start", "Jab", "--length", "0"], out, "--length")
    _fails(capsys, g + ["--start", "Jab", "--format", "xml"], out, "--format")
    _fails(capsys, g + ["--start", "Jab", "--model", "c"], out, "--model")
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"kind": "something"}))
    _fails(capsys, ["generate", "--style", str(bad), "--start", "Jab", "--out", str(out)], out, "kind: expected 'vidstyle.style'")
    _fails(capsys, ["generate", "--style", str(tmp_path / "none.json"), "--out", str(out)], out, "not found")


def test_bad_learn_input(tmp_path, capsys):
    out = tmp_path / "style.json"
    rng = np.random.default_rng(0)
    good = []
    for a in rng.integers(0, 6, size=30):
        good += [CLASSES[a]] * 8 + ["Guard"] * 4
    ok = _label_file(tmp_path / "ok.json", good)
    learn = ["learn-style", "--out", str(out), "--n-init", "1", "--modes", "1-2"]
    _fails(capsys, learn + [_label_file(tmp_path / "empty.json", [])], out, "labels: expected at least 1 item(s), got 0")
    _fails(capsys, learn + [_label_file(tmp_path / "one.json", ["Jab"] * 40)], out, "at least 2 events")
    single = (["Jab"] * 8 + ["Guard"] * 4) * 10
    _fails(capsys, learn + [_label_file(tmp_path / "single.json", single)], out, "2 different actions")
    _fails(capsys, learn + [_label_file(tmp_path / "idle.json", ["Guard"] * 50)], out, "no action events")
    other = _label_file(tmp_path / "other.json", ["Jab", "Kick"] * 5, classes=["Jab", "Kick", "Guard"])
    _fails(capsys, learn + [ok, other], out, "differ from")
    _fails(capsys, learn + [_label_file(tmp_path / "x.json", ["Jab", "Kick"])], out, "labels[1]: 'Kick' is not one of the classes")
    _fails(capsys, learn + [ok, "--min-run", "0"], out, "--min-run")
    _fails(capsys, learn + [ok, "--modes", "x"], out, "--modes")
    _fails(capsys, learn + [str(tmp_path / "missing.json")], out, "file not found")
    # a class that never occurs in training: learning works, generating from it is refused
    no_kick = [x for x in good if x != "RoundhouseKick"]
    assert main(learn + [_label_file(tmp_path / "nokick.json", no_kick)]) == 0
    capsys.readouterr()  # its logs (stderr) are not part of the next command's error
    _fails(capsys, ["generate", "--style", str(out), "--start", "RoundhouseKick"], None, "never occurs")
    assert main(["generate", "--style", str(out), "--start", "Jab", "--length", "30"]) == 0


def test_learn_style_per_performer_from_a_dataset(dataset, tmp_path):
    out_dir = tmp_path / "styles"
    assert main(["learn-style", "--dataset", str(dataset), "--out-dir", str(out_dir), "--n-init", "1",
                 "--modes", "1-2"]) == 0
    assert sorted(p.name for p in out_dir.iterdir()) == ["p00.json", "p01.json"]
    # the per-performer file equals learning from that performer's files directly
    single = tmp_path / "p01.json"
    labels = [str(dataset / "labels" / f"p01_perf{i}.json") for i in range(2)]
    assert main(["learn-style", *labels, "--out", str(single), "--n-init", "1", "--modes", "1-2"]) == 0
    a, b = json.loads((out_dir / "p01.json").read_text()), json.loads(single.read_text())
    assert a["model_a"]["transition"] == b["model_a"]["transition"] and a["n_events"] == b["n_events"]
    assert a["performer"] == "p01"


def test_learn_style_names_the_performer_of_recognised_labels(dataset, tmp_path):
    # recognised label files carry no performer; the dataset's performer id goes into the style
    rec = tmp_path / "rec"
    rec.mkdir()
    manifest = json.loads((dataset / "dataset.json").read_text())
    for v in manifest["videos"]:
        if v["kind"] == "performance":
            doc = json.loads((dataset / v["labels"]).read_text())
            doc.pop("performer", None)
            (rec / f"{v['id']}.json").write_text(json.dumps(doc))
    out_dir = tmp_path / "styles"
    assert main(["learn-style", "--dataset", str(dataset), "--labels-dir", str(rec), "--out-dir", str(out_dir),
                 "--n-init", "1", "--modes", "1-2"]) == 0
    assert [json.loads((out_dir / f"{p}.json").read_text())["performer"] for p in ("p00", "p01")] == ["p00", "p01"]


def test_learn_style_dataset_mode_errors_write_nothing(dataset, tmp_path, capsys):
    out_dir = tmp_path / "styles"
    # recognised labels requested but missing: nothing written
    assert main(["learn-style", "--dataset", str(dataset), "--out-dir", str(out_dir),
                 "--labels-dir", str(tmp_path / "none")]) == 2
    assert "recognised labels of video p00_perf0 (performer p00) not found" in capsys.readouterr().err
    assert not out_dir.exists()
    assert main(["learn-style", "--dataset", str(dataset), "--out", str(tmp_path / "x.json")]) == 2
    assert main(["learn-style"]) == 2


def test_library_with_defaults_is_the_cli(dataset, tmp_path, capsys):
    """vidstyle.style.learn / generate_sequence with the defaults of style/defaults.py give the files and
    sequences of `vidstyle learn-style` / `vidstyle generate` with theirs."""
    import dataclasses
    import inspect

    import typer.main

    from vidstyle.cli import app
    from vidstyle.formats.sequence import format_sequence
    from vidstyle.style import defaults as D
    from vidstyle.style import generate_sequence, learn, style_params
    from vidstyle.style.artifact import StyleParams
    from vidstyle.style.events import EventParams

    labels = [dataset / "labels" / f"p00_perf{i}.json" for i in range(2)]
    assert main(["learn-style", *map(str, labels), "--out", str(tmp_path / "cli.json")]) == 0
    [(pid, style)] = learn(labels)
    style.save(tmp_path / "lib.json")
    assert pid is None and (tmp_path / "lib.json").read_text() == (tmp_path / "cli.json").read_text()
    capsys.readouterr()
    assert main(["generate", "--style", str(tmp_path / "cli.json")]) == 0
    cli_text = capsys.readouterr().out
    seq = generate_sequence(style, style_path=tmp_path / "cli.json")
    assert format_sequence(seq, "text") == cli_text
    # one set of defaults: the module, the library's parameter objects, the library calls and the CLI
    assert style_params() == StyleParams(k_range=(1, 2, 3, 4, 5, 6))
    assert dataclasses.asdict(StyleParams()) == dataclasses.asdict(style_params())
    assert EventParams().ignore == D.IGNORE and EventParams().min_run == D.MIN_RUN
    cmd = {p.name: p.default for p in typer.main.get_command(app).commands["learn-style"].params}
    lib = inspect.signature(style_params).parameters
    for name in ("min_confidence", "min_run", "max_gap", "split_repeats", "seed", "n_init", "n_iter", "alpha",
                 "learn_emission", "emission_prior", "modes", "mode_criterion"):
        assert cmd[name] == lib[name].default, name
    assert cmd["ignore"] == ",".join(lib["ignore"].default)
    gen = {p.name: p.default for p in typer.main.get_command(app).commands["generate"].params}
    sig = inspect.signature(generate_sequence).parameters
    assert (gen["length"], gen["model"], gen["seed"]) == (sig["length"].default, sig["model"].default, sig["seed"].default)


@pytest.mark.parametrize("fmt", ["json", "text"])
def test_generate_several_styles_in_one_run_writes_what_single_runs_write(dataset, tmp_path, capsys, fmt):
    """generate --style A --style B --out-dir D (the pipeline's generate stage, one process for every
    performer) writes D/<style stem>.<format> byte-identical to a run per style with --out."""
    styles = tmp_path / "styles"
    assert main(["learn-style", "--dataset", str(dataset), "--out-dir", str(styles), "--n-init", "1",
                 "--modes", "1-2"]) == 0
    paths = sorted(styles.iterdir())
    out_dir = tmp_path / "generated"
    opts = ["--length", "15", "--seed", "4", "--format", fmt]
    assert main(["generate", *[x for p in paths for x in ("--style", str(p))], *opts, "--out-dir", str(out_dir)]) == 0
    suffix = {"json": ".json", "text": ".txt"}[fmt]
    assert sorted(p.name for p in out_dir.iterdir()) == [p.stem + suffix for p in paths]
    for p in paths:
        single = tmp_path / f"single_{p.stem}{suffix}"
        assert main(["generate", "--style", str(p), *opts, "--out", str(single)]) == 0
        assert (out_dir / f"{p.stem}{suffix}").read_bytes() == single.read_bytes()
    capsys.readouterr()
    # several styles need --out-dir; --out and --out-dir together are refused; nothing is written
    bad = tmp_path / "bad"
    _fails(capsys, ["generate", "--style", str(paths[0]), "--style", str(paths[1]), *opts], None, "--out-dir")
    _fails(capsys, ["generate", "--style", str(paths[0]), *opts, "--out", str(bad / "x"), "--out-dir", str(bad)],
           None, "not both")
    assert not bad.exists()
