"""Behaviour style commands: ``learn-style``, ``generate`` and ``evaluate style``.

    vidstyle learn-style labels/p03_*.json --out style.json
    vidstyle generate --style style.json --start Jab --length 40 --seed 1 --format text
    vidstyle evaluate style --dataset DIR [--labels-dir RECOGNISED] --out metrics.json
"""

from __future__ import annotations

import contextlib
import logging
from pathlib import Path

import typer

from ..errors import InputError
from ..style import defaults as D
from ._evaluate import evaluate_app
from ._numbers import jobs_option

log = logging.getLogger(__name__)

FORMATS = ("text", "json", "csv")


def _style_params(
    ignore: str, min_confidence: float, min_run: int, max_gap: int, split_repeats: bool, seed: int,
    n_init: int, n_iter: int, alpha: float, learn_emission: bool, emission_prior: float, modes: str,
    mode_criterion: str,
):
    from ..style.learn import style_params

    return style_params(ignore, min_confidence, min_run, max_gap, split_repeats, seed, n_init, n_iter, alpha,
                        learn_emission, emission_prior, modes, mode_criterion)


# option declarations shared by learn-style and evaluate style
_IGNORE = typer.Option(",".join(D.IGNORE), "--ignore", help="Comma-separated filler classes that are not actions.")
_MIN_CONF = typer.Option(D.MIN_CONFIDENCE, "--min-confidence", help="Frames below this confidence are dropped.")
_MIN_RUN = typer.Option(D.MIN_RUN, "--min-run", help="Runs shorter than this (frames) are noise.")
_MAX_GAP = typer.Option(D.MAX_GAP, "--max-gap", help="A run resumed after at most this many noise frames is one event.")
_SPLIT = typer.Option(D.SPLIT_REPEATS, "--split-repeats/--no-split-repeats",
                      help="Cut runs of several back-to-back occurrences of an action into events.")
_SEED = typer.Option(D.SEED, "--seed", help="Seed of every random choice (restarts, folds, sampling).")
_N_INIT = typer.Option(D.N_INIT, "--n-init", help="EM restarts per model; the best training likelihood is kept.")
_N_ITER = typer.Option(D.N_ITER, "--n-iter", help="Maximum EM iterations per restart.")
_ALPHA = typer.Option(D.ALPHA, "--alpha", help="Dirichlet pseudo-count per transition cell (smoothing).")
_LEARN_E = typer.Option(D.LEARN_EMISSION, "--learn-emission/--fixed-emission",
                        help="Model (a): learn recognition confusions (else emissions = identity).")
_E_PRIOR = typer.Option(D.EMISSION_PRIOR, "--emission-prior", help="Model (a): pseudo-events per row of the diagonal prior.")
_MODES = typer.Option(D.MODES, "--modes", help="Model (b): candidate numbers of behaviour modes, e.g. 1-6.")
_CRIT = typer.Option(D.MODE_CRITERION, "--mode-criterion", help="Model (b): choose modes by 'heldout' or 'bic'.")


def learn_style(
    labels: list[Path] = typer.Argument(None, help="Label files (JSON, one per video) of one performer."),
    out: Path = typer.Option(None, "--out", "-o", help="Where to write style.json (with LABELS)."),
    dataset: Path = typer.Option(
        None, "--dataset", help="Dataset directory (dataset.json): learn one style per performer from its performances."
    ),
    labels_dir: Path = typer.Option(
        None, "--labels-dir", help="With --dataset: recognised label files <video id>.json (default: ground truth)."
    ),
    out_dir: Path = typer.Option(None, "--out-dir", help="With --dataset: write <performer>.json here."),
    views: str = typer.Option(None, "--views", help="With --dataset: only these views (comma-separated)."),
    ignore: str = _IGNORE,
    min_confidence: float = _MIN_CONF,
    min_run: int = _MIN_RUN,
    max_gap: int = _MAX_GAP,
    split_repeats: bool = _SPLIT,
    seed: int = _SEED,
    n_init: int = _N_INIT,
    n_iter: int = _N_ITER,
    alpha: float = _ALPHA,
    learn_emission: bool = _LEARN_E,
    emission_prior: float = _E_PRIOR,
    modes: str = _MODES,
    mode_criterion: str = _CRIT,
    poses_dir: Path = typer.Option(None, "--poses-dir", help="With LABELS: 2D poses <video stem>.poses.json of the "
                                   "labelled videos; fits the action-level style (needs --action-model)."),
    action_model: Path = typer.Option(None, "--action-model", help="With --poses-dir: the action model "
                                      "(vidstyle fit-actions, orthodox) whose coefficients are fitted."),
    population: Path = typer.Option(None, "--population", help="With --poses-dir: a dataset directory whose "
                                    "videos' true 2D and labels give the population's guard / stance / crouch per "
                                    "view and action durations (default: raw figures, durations of the model)."),
    population_performers: str = typer.Option(None, "--population-performers",
                                              help="With --population: only these performers (comma-separated)."),
    jobs: int = jobs_option(-1, help="With --dataset: performers learned in parallel (-1 = all cores; the "
                            "styles do not depend on it)."),
) -> None:
    """Learn a performer's action style (HMMs + durations) from frame labels.

    Either LABELS... --out style.json (one performer), or --dataset DIR --out-dir DIR [--labels-dir REC]
    (one <performer>.json per performer of the dataset, from its performance videos).
    """
    from ..style.learn import learn

    params = _style_params(ignore, min_confidence, min_run, max_gap, split_repeats, seed, n_init, n_iter,
                           alpha, learn_emission, emission_prior, modes, mode_criterion)
    # learn everything first, write afterwards: a bad file leaves no partial set of outputs
    if dataset is None:
        if not labels or out is None:
            raise InputError("learn-style: give LABELS... --out FILE, or --dataset DIR --out-dir DIR")
    elif labels or out is not None or out_dir is None:
        raise InputError("learn-style: with --dataset give --out-dir (and no LABELS or --out)")
    wanted = None if views is None else [v.strip() for v in views.split(",") if v.strip()]
    if (poses_dir is None) != (action_model is None):
        raise InputError("learn-style: --poses-dir and --action-model go together")
    if poses_dir is not None and dataset is not None:
        raise InputError("learn-style: --poses-dir works with LABELS... --out (one performer), not --dataset")
    learned = learn(labels or [], dataset=dataset, labels_dir=labels_dir, views=wanted, params=params, jobs=jobs)
    if poses_dir is not None:
        from ..actionmodel.stylefit import learn_action_style

        est = None
        if population is not None:  # the population's true 2D (dataset truth sidecars) and labels
            import json

            from ..evaluation.actionstyle import fit_population
            from ..formats.dataset import read_dataset

            ds = read_dataset(Path(population) / "dataset.json")
            manifest = json.loads((Path(population) / "dataset.json").read_text())
            pop = ([p.strip() for p in population_performers.split(",") if p.strip()] if population_performers
                   else [p["id"] for p in manifest["performers"]])
            est = fit_population(ds, manifest, pop)
        learned[0][1].action_style = learn_action_style(labels, poses_dir, action_model, est, seed)
    styles = [(out if pid is None else Path(out_dir) / f"{pid}.json", style) for pid, style in learned]
    from ..fileio import output_dir

    # --out-dir: made if missing (removed again, when empty, if writing fails), its stale temporaries swept
    into = output_dir(out_dir, [d for d, _ in styles]) if out_dir is not None else contextlib.nullcontext()
    with into:
        for dest, style in styles:
            style.save(dest)
            log.info("wrote %s (%d events, model (b): %d modes)", dest, int(style.action_counts.sum()),
                     style.model_b.n_modes_)


#: file suffix of a generated sequence per --format (generate --out-dir)
SUFFIXES = {"text": ".txt", "json": ".json", "csv": ".csv"}


def generate(
    style_paths: list[Path] = typer.Option(..., "--style", "-s", metavar="PATH", help="style.json from learn-style; repeat "
                                           "it (with --out-dir) for one sequence per style in one run."),
    start: str | None = typer.Option(None, "--start", help="First action (default: drawn from the model)."),
    length: int = typer.Option(D.GENERATE_LENGTH, "--length", "-n", help="Number of action events."),
    seed: int = typer.Option(D.SEED, "--seed", help="Random seed; the output is a function of it."),
    fmt: str = typer.Option("text", "--format", "-f", help="text (thesis Table 4 style), json or csv."),
    model: str = typer.Option(D.MODEL, "--model", "-m", help="a (thesis HMM), b (behaviour modes) or bigram."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Write here instead of stdout."),
    out_dir: Path | None = typer.Option(None, "--out-dir", help="Write <style stem>.json (.txt, .csv by "
                                        "--format) here, one per --style."),
) -> None:
    """Generate a new action sequence (with durations) in a learned style; with several --style and
    --out-dir, one per style, each the sequence a run with that style alone writes (the same --seed)."""
    from ..fileio import output_dir, outputs_by_stem, write_text
    from ..formats.sequence import format_sequence, write_sequence
    from ..style.artifact import Style
    from ..style.learn import generate_sequence

    if fmt not in FORMATS:
        raise InputError(f"--format: one of {', '.join(FORMATS)}, got {fmt!r}")
    if out_dir is not None and out is not None:
        raise InputError("generate: give --out or --out-dir, not both")
    if len(style_paths) > 1 and out_dir is None:
        raise InputError("generate: several --style need --out-dir")
    dests = outputs_by_stem(style_paths, out_dir, SUFFIXES[fmt]) if out_dir is not None else [out]
    # generate everything first, write afterwards: a bad style file leaves no partial set of outputs
    done = []
    for style_path in style_paths:
        style = Style.load(style_path)
        seq = generate_sequence(style, length, start=start, seed=seed, model=model, style_path=style_path)
        log.info("generated %d events with model %s (seed %d) from %s", len(seq.events), model, seed, style_path)
        done.append(seq)
    into = output_dir(out_dir, dests) if out_dir is not None else contextlib.nullcontext()
    with into:
        for dest, seq in zip(dests, done):
            if dest is not None and fmt == "json":
                write_sequence(dest, seq)
            elif dest is not None:
                write_text(dest, format_sequence(seq, fmt))
            else:
                typer.echo(format_sequence(seq, fmt), nl=False)


@evaluate_app.command("style")
def evaluate_style(
    dataset: Path = typer.Option(..., "--dataset", "-d", help="Directory holding dataset.json."),
    labels_dir: Path | None = typer.Option(
        None, "--labels-dir", help="Recognised label files (<video id>.json); evaluated beside ground truth."),
    out: Path | None = typer.Option(None, "--out", "-o", help="Where to write metrics JSON."),
    model: Path | None = typer.Option(
        None, "--model", "-m", help="With --labels-dir: the recognizer that made the labels; only its split's test "
        "performers are scored on recognised labels (they never trained or tuned it)."),
    performers: str | None = typer.Option(
        None, "--performers", help="With --labels-dir, instead of --model: comma-separated performers to score "
        "(they must be unseen by the recognizer)."),
    heldout_fraction: float = typer.Option(0.34, "--heldout-fraction", help="Share of videos (or events) held out."),
    n_generate: int = typer.Option(20, "--n-generate", help="Generated sequences per performer."),
    generate_length: int = typer.Option(40, "--generate-length", help="Events per generated sequence."),
    ignore: str = _IGNORE,
    min_confidence: float = _MIN_CONF,
    min_run: int = _MIN_RUN,
    max_gap: int = _MAX_GAP,
    split_repeats: bool = _SPLIT,
    seed: int = _SEED,
    n_init: int = _N_INIT,
    n_iter: int = _N_ITER,
    alpha: float = _ALPHA,
    learn_emission: bool = _LEARN_E,
    emission_prior: float = _E_PRIOR,
    modes: str = _MODES,
    mode_criterion: str = _CRIT,
    jobs: int = jobs_option(-1, help="Styles fitted in parallel (-1 = all cores; the metrics do not depend on it)."),
) -> None:
    """Style metrics on performers with known chains: transition error, JSD, identification, likelihood."""
    from ..evaluation.style import EvalParams, evaluate_dataset
    from ..formats.metrics import write_metrics

    if labels_dir is not None and not labels_dir.is_dir():
        raise InputError(f"{labels_dir}: --labels-dir is not a directory")
    sp = _style_params(ignore, min_confidence, min_run, max_gap, split_repeats, seed, n_init, n_iter,
                       alpha, learn_emission, emission_prior, modes, mode_criterion)
    params = EvalParams(style=sp, heldout_fraction=heldout_fraction, n_generate=n_generate,
                        generate_length=generate_length)
    chosen = None
    if labels_dir is not None:
        if (model is None) == (performers is None):
            raise InputError("--labels-dir: give exactly one of --model (its test performers are scored) or --performers")
        if model is not None:
            from ..recognition.recognizer import read_header

            split = (read_header(model).get("split") or {})
            chosen = split.get("test_performers")
            if not chosen:
                raise InputError(f"{model}: the model records no test performers (train it with --dataset)")
        else:
            chosen = [p.strip() for p in performers.split(",") if p.strip()]
    elif model is not None or performers is not None:
        raise InputError("--model/--performers: only used with --labels-dir")
    metrics = evaluate_dataset(dataset, params, labels_dir, chosen, jobs=jobs)
    if out is not None:
        write_metrics(out, metrics)
    _print_table(metrics)


def _print_table(metrics: dict) -> None:
    from rich.console import Console
    from rich.table import Table

    srcs = metrics["sources"]
    names = list(srcs)
    t = Table(title=f"style metrics (seed {metrics['seed']})")
    t.add_column("metric")
    for n in names:
        t.add_column(n.replace("_", " "), justify="right")

    def f(x, fmt="{:.3f}"):
        return "-" if x is None else fmt.format(x)

    def row(label, get, fmt="{:.3f}"):
        t.add_row(label, *(f(get(srcs[n]["summary"]), fmt) for n in names))

    row("performers", lambda s: s["n_performers"], "{:d}")
    row("train / held-out events", lambda s: f"{s['n_train_events']} / {s['n_heldout_events']}", "{}")
    row("transition MAE, model (a)", lambda s: s["transition_mae"]["a"])
    row("transition MAE, bigram", lambda s: s["transition_mae"]["bigram"])
    row("transition MAE, model (b) implied", lambda s: s["transition_mae"]["b_implied"])
    row("duration mean error (frames)", lambda s: s["duration_mean_abs_error_frames"], "{:.2f}")
    for m in ("a", "b"):
        for n in (2, 3):
            row(f"JSD {n}-gram ({m}) same / other",
                lambda s, m=m, n=n: f"{s['fidelity'][m][f'jsd_{n}gram_same']:.3f} / "
                                    f"{s['fidelity'][m][f'jsd_{n}gram_other']:.3f}", "{}")
    row("JSD 2-gram real train vs held-out", lambda s: s["fidelity"]["a"]["jsd_2gram_train_vs_heldout"])
    row("identification (a) by held-out data", lambda s: s["identification"]["a"]["accuracy_by_heldout_data"], "{:.1%}")
    row("identification (a) by true chain", lambda s: s["identification"]["a"]["accuracy_by_true_chain"], "{:.1%}")
    row("identification (b) by held-out data", lambda s: s["identification"]["b"]["accuracy_by_heldout_data"], "{:.1%}")
    row("held-out sequences identified by (a)",
        lambda s: s["identification"]["heldout_sequences_by_model_a"]["accuracy"], "{:.1%}")
    row("held-out loglik/event (a)", lambda s: s["heldout_loglik_per_event"]["a"], "{:.4f}")
    row("held-out loglik/event (b)", lambda s: s["heldout_loglik_per_event"]["b"], "{:.4f}")
    row("held-out loglik/event bigram", lambda s: s["heldout_loglik_per_event"]["bigram"], "{:.4f}")
    row("modes chosen (b)", lambda s: " ".join(str(k) for k in s["n_modes"].values()), "{}")
    Console().print(t)


def register(app: typer.Typer) -> None:
    app.command("learn-style")(learn_style)
    app.command("generate")(generate)
