# Every target creates or reuses .venv and installs what it needs: each works as the first command.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed-core
STAMP_RL := $(VENV)/.installed-rl

.PHONY: setup setup-rl demo test bench bench-compile lint docs notebooks clean

$(STAMP): pyproject.toml
	test -x $(BIN)/python || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[dev]"
	touch $@

$(STAMP_RL): $(STAMP)
	$(BIN)/python -m pip install -q -e ".[dev,rl,notebooks,scale]"
	touch $@

setup: $(STAMP)

setup-rl: $(STAMP_RL)

demo: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python -m jvl_gym.demo --out demo_out

test: $(STAMP_RL)
	JVL_FAST=1 MPLBACKEND=Agg $(BIN)/python -m pytest -n 2 --nbmake tests notebooks

bench: $(STAMP_RL)
	$(BIN)/python benchmarks/bench_sim.py
	$(BIN)/python benchmarks/bench_protocol.py
	$(BIN)/python benchmarks/bench_envs.py
	$(BIN)/python benchmarks/bench_scale.py

bench-compile: $(STAMP_RL)
	$(BIN)/python benchmarks/bench_compile.py

notebooks: $(STAMP_RL)
	cd notebooks && for f in *.py; do ../$(BIN)/jupytext --to ipynb "$$f"; done

docs: $(STAMP)
	$(BIN)/python -m pip install -q -e ".[docs]"
	$(BIN)/python -m jvl_gym.registers.reference docs/registers.md
	$(BIN)/mkdocs build --strict -d site

lint: $(STAMP)
	$(BIN)/ruff check src tuning tests benchmarks

clean:
	rm -rf $(VENV) demo_out .pytest_cache
	find src tuning -name "*.nbi" -delete -o -name "*.nbc" -delete  # numba caches
