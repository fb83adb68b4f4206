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

.PHONY: setup run test bench lint format clean doctor docs docs-gallery browser learned-quick

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/ensure_llvm.sh
	@test -x $(VPY) || $(PY) -m venv $(VENV)
	$(VPY) -m pip install -q --upgrade pip
	$(VPY) -m pip install -q -e '.[dev,docs]'
	bash scripts/ensure_llvm.sh $(VPY)
	@mkdir -p build/drjit-cache
	$(VPY) -m simlunar.cli doctor --short
	@touch $(STAMP)

# the quickstart scene (EXR radiance, PNG preview, ground truth), then the quickstart experiment
run: setup
	$(VPY) -m simlunar.cli render scenes/quickstart_scene.yaml --out results/quickstart_render
	$(VPY) -m simlunar.cli run $(EXPERIMENT)

# the quick learned path: trains the small learned-map model only when it is missing or older
# than its training YAML, then runs experiments/learned_quick.yaml (README, "Experiments")
models/learned_quarter.joblib: experiments/training/learned_quarter.yaml | setup
	$(VPY) -m simlunar.cli train experiments/training/learned_quarter.yaml

learned-quick: setup models/learned_quarter.joblib
	$(VPY) -m simlunar.cli run experiments/learned_quick.yaml

test: setup browser
	$(VPY) -m pytest $(PYTEST_ARGS)

bench: setup
	$(VPY) benchmarks/run.py $(if $(ONLY),--only $(ONLY),)

lint: setup
	$(VENV)/bin/ruff check .
	$(VENV)/bin/ruff format --check simlunar tests benchmarks

format: setup
	$(VENV)/bin/ruff check --fix .
	$(VENV)/bin/ruff format simlunar tests benchmarks

# the documentation site: build/docs/html/index.html (Sphinx, warnings are errors). The
# configuration reference in docs/experiments.md is refreshed from the schema first, the
# experiment catalogue in README.md and docs/experiments.md from experiments/*.yaml; the
# gallery shows results/<experiment>/figures, or, when the quickstart has none, a small
# quickstart run made here once (build/docs-runs/quickstart, about 30 s of CPU; figures are
# results and never committed)
docs: setup docs-gallery
	$(VPY) -c "from simlunar.config.docs import update_docs; update_docs('docs/experiments.md')"
	$(VPY) -m simlunar.config.catalogue README.md docs/experiments.md
	$(VPY) -m sphinx -b html -W --keep-going -q docs build/docs/html
	@echo "docs: build/docs/html/index.html"

docs-gallery: setup
	$(VPY) docs/_ext/simlunar_docs.py

# headless Chromium for the browser tests of the site and the reports (Debian's package;
# as root, as in CI; elsewhere install it yourself or the tests skip, saying so)
browser:
	@command -v chromium >/dev/null || { [ "$$(id -u)" = 0 ] && apt-get update -qq && \
	  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium > /dev/null; } || \
	  echo "browser: chromium not installed (not root); the browser tests will skip"

doctor: setup
	$(VPY) -m simlunar.cli doctor

clean:
	rm -rf build results .pytest_cache .ruff_cache
