# Two commands for a fresh machine: `make demo` and `make test`. Both create .venv when needed.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
CORESTAMP := $(VENV)/.installed-core
NBSTAMP := $(VENV)/.installed-notebooks
DOCSTAMP := $(VENV)/.installed-docs

.PHONY: demo test test-all fuzz lint models bench docs clean

# The core install runs the demo; the suite adds the dev tools and the cluster extra (Dask).
$(CORESTAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e .
	touch $(CORESTAMP)

$(STAMP): $(CORESTAMP)
	$(BIN)/python -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

$(NBSTAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[dev,notebooks]'
	touch $(NBSTAMP)

$(DOCSTAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -e '.[dev,docs]'
	touch $(DOCSTAMP)

demo: $(CORESTAMP)
	$(BIN)/twin agard demo --out out/demo
	# a "measured" SRS (its IMU filters the gyros) diagnosed against the nominal SRS
	for n in 1 2; do $(BIN)/twin simulate notebooks/data/srs-imu-filtered.json --quiet \
	  --signal multisine$$n-pitch --model reduced --seed $$n --overwrite \
	  --out out/demo/recorded-pitch-$$n --rrd out/demo/recorded-pitch-$$n.rrd > /dev/null \
	  || exit 1; done
	$(BIN)/twin diagnose out/demo/recorded-pitch-1 out/demo/recorded-pitch-2 --config srs \
	  --out out/demo/diagnosis --save-config out/demo/srs-measured.json
	# a pilot flying the pitch task behind the MPI's 1 Hz filter, 35 ms and noise (Table 6.3, 8)
	$(BIN)/twin pilot run condition-8 --quiet --rrd out/demo/pilot-condition-8.rrd \
	  --out out/demo/pilot-condition-8.csv > /dev/null

test: $(STAMP)
	$(BIN)/python -m pytest -q

test-all: $(NBSTAMP)
	$(BIN)/python -m pytest -q -m ''

fuzz: $(STAMP)
	$(BIN)/python -m pytest -q -n 0 -s -m "" tests/test_fuzz_inputs.py tests/test_fuzz_outputs.py

lint: $(STAMP)
	$(BIN)/ruff check twin tests bench docs
	$(BIN)/ruff format --check twin tests bench docs
	$(BIN)/lint-imports

# The docs site in docs/_build/html: the figures and notebooks first (docs/figures.py makes
# only those whose sources changed; all of them: about 15 min on two cores), then Sphinx with
# warnings as errors.
docs: $(DOCSTAMP)
	$(BIN)/python docs/figures.py
	rm -rf docs/reference/generated  # the API pages are generated anew: none of a moved module
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs docs/_build/html

models: $(STAMP)
	$(BIN)/python -m twin.platform.build

bench: $(STAMP)
	$(BIN)/python bench/kinematics_throughput.py
	$(BIN)/python bench/twin_throughput.py
	$(BIN)/python bench/blas_threads.py
	$(BIN)/python bench/agard_sweep.py
	$(BIN)/python bench/pilot_montecarlo.py
	$(BIN)/python bench/distributed_montecarlo.py
	$(BIN)/python bench/diagnose_run.py

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache build *.egg-info docs/_build docs/_figures \
	  docs/notebooks docs/reference/generated docs/reference/_api_modules.rst
