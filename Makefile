# simlunar: `make run` and `make test` each set everything up on a fresh machine.
SHELL := /bin/bash
PY ?= python3
VENV := .venv
VPY := $(VENV)/bin/python
STAMP := $(VENV)/.simlunar-setup
export DRJIT_CACHE_DIR ?= $(CURDIR)/build/drjit-cache
export MPLBACKEND ?= Agg
ONLY ?=
EXPERIMENT ?= experiments/quickstart.yaml
PYTEST_ARGS ?=

.PHONY: setup run test bench lint format clean doctor

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/ensure_llvm.sh
	@test -x $(VPY) || $(PY) -m venv $(VENV)
	$(VPY) -m pip install -q --upgrade pip
	$(VPY) -m pip install -q -e '.[dev]'
	bash scripts/ensure_llvm.sh $(VPY)
	@mkdir -p build/drjit-cache
	$(VPY) -m simlunar.cli doctor --short
	@touch $(STAMP)

# the quickstart scene (EXR radiance, PNG preview, ground truth), then the quickstart experiment
run: setup
	$(VPY) -m simlunar.cli render scenes/quickstart_scene.yaml --out results/quickstart_render
	$(VPY) -m simlunar.cli run $(EXPERIMENT)

test: setup
	$(VPY) -m pytest $(PYTEST_ARGS)

bench: setup
	$(VPY) benchmarks/run.py $(if $(ONLY),--only $(ONLY),)

lint: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check simlunar tests benchmarks

format: setup
	$(VENV)/bin/ruff check --fix .
	$(VENV)/bin/ruff format simlunar tests benchmarks

doctor: setup
	$(VPY) -m simlunar.cli doctor

clean:
	rm -rf build results .pytest_cache .ruff_cache
