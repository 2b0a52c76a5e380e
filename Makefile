# Every target creates or reuses .venv and installs what it needs: each works as the first command.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-core
STAMP_RL := $(VENV)/.installed-rl

.PHONY: setup setup-rl demo results test bench bench-compare bench-compile lint docs notebooks clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[dev]"
	touch $@

# numba compiles every environment's step (once per machine, cached) while pip installs the
# extras: the compile needs only the core, and the extras change no core package.
$(STAMP_RL): $(STAMP)
	$(BIN)/jvl-gym compile & compile=$$!; \
	$(BIN)/python -m pip install -q -e ".[dev,rl,notebooks,test,scale,canopen,studio]" \
	  && $(BIN)/python -m pip install -q --no-deps "jvlmotor==0.1.3" \
	  || { kill $$compile; exit 1; }; \
	wait $$compile
	touch $@

setup: $(STAMP)
	$(BIN)/jvl-gym compile --motors-only  # numba: every family's kernel (cached: seconds after once)

setup-rl: $(STAMP_RL)

demo: $(STAMP)
	$(BIN)/jvl-gym compile --motor MAC140  # numba: only the family of the demo's motor (jvl_gym.cli.demo.MOTOR)
	MPLBACKEND=Agg $(BIN)/python -m jvl_gym.cli.demo --out demo_out

# every env × family × {trained policies, baseline, random}: docs/results.md and its plots
results: $(STAMP_RL)
	MPLBACKEND=Agg $(BIN)/jvl-gym evaluate --all --out docs

# three workers on two cores: many tests wait on twins running in real time, on Chromium or on
# Ray; worksteal moves queued tests to whichever worker is idle
test: $(STAMP_RL)
	JVL_FAST=1 MPLBACKEND=Agg $(BIN)/python -m pytest -n 3 --dist worksteal --nbmake tests notebooks

bench: $(STAMP_RL)
	$(BIN)/python benchmarks/bench_sim.py
	$(BIN)/python benchmarks/bench_protocol.py
	$(BIN)/python benchmarks/bench_envs.py
	$(BIN)/python benchmarks/bench_scaling.py
	$(BIN)/python benchmarks/bench_scale.py
	$(BIN)/python benchmarks/bench_studio.py
	@echo "figures written to docs/benchmarks.md"

# this tree beside the reference (benchmarks/REFERENCE) and BASELINE=<git revision> (default
# HEAD~1), in one run
bench-compare: $(STAMP_RL)
	$(BIN)/python benchmarks/bench_compare.py $(or $(BASELINE),HEAD~1)

# BASELINE=<git revision> measures that revision beside this tree
bench-compile: $(STAMP_RL)
	$(BIN)/python benchmarks/bench_compile.py $(if $(BASELINE),--baseline $(BASELINE))

notebooks: $(STAMP_RL)
	cd notebooks && for f in *.py; do ../$(BIN)/jupytext --to ipynb "$$f"; done

docs: $(STAMP)
	$(BIN)/python -m pip install -q -e ".[docs]"
	$(BIN)/python -m jvl_gym.families.mac050_141.reference docs/registers.md
	$(BIN)/python -m jvl_gym.families.reference docs/families
	$(BIN)/mkdocs build --strict -d site

lint: $(STAMP)
	$(BIN)/ruff check src tuning tests benchmarks

clean:
	rm -rf $(VENV) demo_out .pytest_cache
	find src tuning tests -name "*.nbi" -delete -o -name "*.nbc" -delete  # numba caches
