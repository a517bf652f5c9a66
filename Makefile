# lanelib: `make demo` runs the pipeline on the bundled data, `make test` runs every test.
# Both create the virtual environment (.venv) and install what they need on first use.

PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
OUT    ?= out
# Udacity data for the real-data tests and benchmarks (skipped when absent)
export LANELIB_DATA ?= $(abspath ../shared/data)

.PHONY: demo test bench lab venv clean

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
	@echo "annotated images and results.json are in $(OUT)/"

test: $(STAMP)
	$(PY) -m pytest -q -n 2 --dist loadfile tests

bench: $(STAMP)
	$(PY) -m lanelib bench

lab: $(STAMP)
	$(VENV)/bin/jupyter lab notebooks/

clean:
	rm -rf $(OUT) .pytest_cache
