# ScourSPH: the two commands a new user runs are `make run` and `make test`.
PYTHON ?= python3.11
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# make run's main job: the saturated plunging scour at 5 mm (q = 0.11) to END s. Another SCENE runs
# to its own scene.end_time unless END is given; THREADS: Numba threads (2, or 1 on a 1-core machine)
MAIN_SCENE := scenes/scour_plunging_saturated.toml
SCENE  ?= $(MAIN_SCENE)
ifeq ($(SCENE),$(MAIN_SCENE))
END    ?= 0.2
# the pore water's density diffusion: without it a pore-water particle at the bed's top corner by the end
# wall was thrown out at 5e5 m/s at t = 0.19 s on 2 threads (the pore-water instability of issue 34; the
# mobile-bed dam break holds with it, verification/results/mobile_bed_dam_break/README.md)
MAIN_ARGS := --set numerics.pore_density_diffusion=antuono
endif
NPROC  := $(shell getconf _NPROCESSORS_ONLN 2>/dev/null || echo 1)
THREADS ?= $(if $(filter 1,$(NPROC)),1,2)
# OpenMP's threads wait asleep, not spinning: with another busy process on the cores, spinning made
# 2 threads 30 times slower than 1 (docs/scour_plunging.md, "make run")
OMP_WAIT_POLICY ?= PASSIVE
OUT    ?= runs/$(basename $(notdir $(SCENE)))
RUN_ARGS ?=
NIGHTLY ?= runs/nightly

.PHONY: run test lint format bench bench-check bench-baseline nightly verify references clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

## make run: set up .venv and run the main job, the saturated plunging scour (q = 0.11, 5 mm) to END s,
## in runs/scour_plunging_saturated/: scour.csv (d(t)), scour.png (surfaces, d(t)), scour_hole.png (the
## hole). SCENE=scenes/scour_saturated.toml: the seed's 0.025 s; END=, THREADS=, OUT=, RUN_ARGS= override
run: $(STAMP)
	OMP_WAIT_POLICY=$(OMP_WAIT_POLICY) $(BIN)/scoursph run $(SCENE) --out $(OUT) --overwrite --threads $(THREADS) \
		$(if $(END),--set scene.end_time=$(END)) $(MAIN_ARGS) $(RUN_ARGS)

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
