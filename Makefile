# ScourSPH: the two commands a new user runs are `make run` and `make test`.
PYTHON ?= python3.11
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
SCENE  ?= scenes/scour_saturated.toml
OUT    ?= runs/scour_saturated
NIGHTLY ?= runs/nightly

.PHONY: run test lint format bench bench-check bench-baseline nightly verify references clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

## make run: set up .venv and run the main job, the seed's saturated scour at q = 0.11 for its 0.025 s
## (scour depth in runs/scour_saturated/scour.csv, scour.png); SCENE=scenes/dam_break_2d.toml for the dam break
run: $(STAMP)
	$(BIN)/scoursph run $(SCENE) --out $(OUT) --overwrite

## make test: set up .venv, check the style (ruff, fast), run the test suite
test: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/python -m pytest -q

## make lint: the style checks alone; make format rewrites the files to the style
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .

format: $(STAMP)
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

## make bench: performance benchmarks (pytest-benchmark), results in .benchmarks/
bench: $(STAMP)
	$(BIN)/python -m pytest benchmarks -q --benchmark-only --benchmark-autosave -p no:cacheprovider -o addopts="" -o python_files="bench_*.py" -s

## make bench-check: the benchmark regression gate (ratios to a calibration kernel timed alongside;
## benchmarks/gate.py, docs/benchmarks.md); exit status 1 on a regression
bench-check: $(STAMP)
	$(BIN)/python benchmarks/gate.py check --json $(NIGHTLY)/bench-latest.json

## make bench-baseline: re-measure the gate's baseline and thresholds (10 runs of the gate suite), then
## the spread of the side-by-side timing against the new baseline commit's build (10 runs; about an hour in all)
bench-baseline: $(STAMP)
	$(BIN)/python benchmarks/gate.py baseline --runs 10
	$(BIN)/python benchmarks/gate.py reference-baseline --runs 10

## make nightly: the benchmark gate, then every verification case and its study (scoursph report):
## $(NIGHTLY)/<date>/index.html and results.json, $(NIGHTLY)/latest; exit 1 on a failure or regression
nightly: $(STAMP)
	@rm -f $(NIGHTLY)/bench-latest.json; status=0; \
	$(BIN)/python benchmarks/gate.py check --json $(NIGHTLY)/bench-latest.json || status=1; \
	$(BIN)/scoursph report --out $(NIGHTLY) --bench-json $(NIGHTLY)/bench-latest.json || status=1; \
	exit $$status

## make verify: every verification case at its default resolution
verify: $(STAMP)
	$(BIN)/scoursph verify all

## make references: regenerate the OpenFOAM and LIGGGHTS reference data (long)
references: $(STAMP)
	$(BIN)/python -m reference_cases.run_all --nice 10

clean:
	rm -rf runs .pytest_cache .benchmarks
