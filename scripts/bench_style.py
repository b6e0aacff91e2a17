"""Benchmark of the behaviour-style models (issue 5): fit and score time vs number of events.

Prints machine info and the median of >= 5 runs after a warm-up for the closed-form bigram, the thesis
HMM (a) (hmmlearn EM, states = actions, learned confusion emission) and the behaviour-mode HMM (b) with
a fixed K and with K selection; the ratio to the bigram is the cost of EM. Data: a synthetic chain.

    python scripts/bench_style.py [--events 500 2000 8000] [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np

from vidstyle.style.models import ActionHMM, BigramModel, ModeHMM
from vidstyle.style.synthetic import random_chain, sample_chain


def _median_time(fn, repeats: int) -> float:
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--events", type=int, nargs="+", default=[500, 2000, 8000])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"numpy {np.__version__}, python {platform.python_version()}")
    try:
        from threadpoolctl import threadpool_info

        print("BLAS:", ", ".join(f"{i['internal_api']} ({i['num_threads']} threads)" for i in threadpool_info()))
    except ImportError:
        print("BLAS: unknown (threadpoolctl not installed)")
    rng = np.random.default_rng(args.seed)
    chain = random_chain(rng)
    models = {
        "bigram": lambda: BigramModel(6),
        "(a) action HMM, n_init=4": lambda: ActionHMM(6, n_init=4, random_state=0),
        "(b) mode HMM K=6, n_init=4": lambda: ModeHMM(n_modes=6, n_actions=6, n_init=4, random_state=0),
        "(b) mode HMM K=1..6 held-out": lambda: ModeHMM(n_actions=6, n_init=4, random_state=0),
    }
    print(f"{'events':>7} {'model':<32} {'fit s':>9} {'x bigram':>9} {'score ms':>9}")
    for n in args.events:
        seqs = [sample_chain(chain["start"], chain["transition"], n // 4, rng) for _ in range(4)]
        base = None
        for name, make in models.items():
            reps = args.repeats if "K=1..6" not in name or n <= 2000 else max(1, args.repeats // 5)
            t_fit = _median_time(lambda make=make, seqs=seqs: make().fit(seqs), reps)
            fitted = make().fit(seqs)
            t_score = _median_time(lambda fitted=fitted, seqs=seqs: fitted.score(seqs), args.repeats)
            base = t_fit if base is None else base
            print(f"{n:>7} {name:<32} {t_fit:>9.4f} {t_fit / base:>9.0f} {1e3 * t_score:>9.2f}")


if __name__ == "__main__":
    main()
