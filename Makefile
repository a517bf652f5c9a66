# lanelib: `make demo` runs the pipeline on the bundled data, `make test` runs every test.
# Both create the virtual environment (.venv) and install what they need on first use.

PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
OUT    ?= out
# Udacity data for the real-data tests and benchmarks (skipped when absent)
export LANELIB_DATA ?= $(abspath ../shared/data)

.PHONY: demo test portability bench scoreboard ablation lab venv clean e2e-deps

venv: $(STAMP)

$(STAMP): requirements.txt pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements.txt
	$(PY) -m pip install -q --no-deps -e .
	touch $(STAMP)

demo: $(STAMP)
	$(PY) -m lanelib calibrate camera_cal -o $(OUT)/calibration.json
	$(PY) -m lanelib images test_images -o $(OUT)/images --calibration $(OUT)/calibration.json
	$(PY) -m lanelib video videos/project.mp4 -o $(OUT)/project.mp4 --calibration $(OUT)/calibration.json \
		--log $(OUT)/project_frames.csv
	$(PY) -m lanelib evaluate video videos/project.mp4
	@echo "annotated images, results.json, the tracked video and its per-frame log are in $(OUT)/"

NBVAL := $(PY) -m pytest -q -n 2 --dist loadfile --nbval --nbval-current-env --nbval-cell-timeout=300

test: $(STAMP) e2e-deps
	$(NBVAL) --doctest-modules tests notebooks lanelib
	@$(MAKE) --no-print-directory portability

# The notebooks' outputs must replay on every machine, not only the one that wrote them. Replay
# them once more on other kernels: OpenBLAS's oldest x86-64 kernel (Prescott) on one thread, and
# OpenCV without its AVX/AVX2/AVX-512 code paths; on an AVX-512 CPU also OpenBLAS's SkylakeX
# kernel (the one that once printed 7e-15 where the committed output said 9e-16).
PORTABLE_ENV := OPENBLAS_CORETYPE=Prescott OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 \
	OPENCV_CPU_DISABLE=AVX512-SKX,AVX2,FP16,AVX,SSE4.2,SSE4.1
portability: $(STAMP)
	@echo "portability: notebooks replayed with $(PORTABLE_ENV)"
	env $(PORTABLE_ENV) $(NBVAL) -p no:cacheprovider notebooks
	@if grep -qw avx512f /proc/cpuinfo 2>/dev/null; then \
	  echo "portability: notebooks replayed with OPENBLAS_CORETYPE=SkylakeX"; \
	  env OPENBLAS_CORETYPE=SkylakeX $(NBVAL) -p no:cacheprovider notebooks; \
	else echo "portability: no AVX-512 on this CPU; the SkylakeX replay is skipped"; fi

# The browser test of the sliders (tests/e2e) drives Debian's chromium through Playwright (never
# Playwright's own browser download). Installed here when missing and we are root with apt-get
# (as on CI); otherwise a note says what to install and the test skips. Silent when present.
CHROMIUM ?= /usr/bin/chromium
e2e-deps:
	@if [ -x "$(CHROMIUM)" ]; then :; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
	  echo "e2e-deps: installing Debian chromium for tests/e2e (apt-get)"; \
	  { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; } \
	    || { echo "e2e-deps: apt-get install chromium failed"; [ "$$CI" != true ] || exit 1; }; \
	else \
	  echo "e2e-deps: $(CHROMIUM) not found; tests/e2e will skip. Install it with: sudo apt-get install chromium"; \
	fi

bench: $(STAMP)
	$(PY) -m lanelib bench

# One table of lanelib on every data set at hand, real data first (rows without their data are skipped)
scoreboard: $(STAMP)
	$(PY) -m lanelib scoreboard --out $(OUT)/scoreboard --json $(OUT)/scoreboard.json

# each part switched alone on every scoreboard row (about a minute per part); the table and the
# figures go to docs/, where docs/results.md and notebook 09 show them
ablation: $(STAMP)
	$(PY) -m lanelib ablation --out $(OUT)/ablation --workers 2 --json docs/ablation.json \
		--markdown docs/ablation.md

lab: $(STAMP)
	$(VENV)/bin/jupyter lab notebooks/

clean:
	rm -rf $(OUT) .pytest_cache
