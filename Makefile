# Two entry points: `make demo` runs the mission in the simulated world, `make test` runs
# the tests. Both install what is missing first: Debian packages (only those missing), a
# .venv, the project. The demo's environment is the light one: the base package and its
# voice, no test tools, robot SDKs or Ray; `make test` adds those to the same .venv.
# `make test-fast` is the quick loop: the same suite without the tests marked slow.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
# open3d needs libusb, libGL/EGL/X11 and libgomp; pyttsx3 speaks through espeak-ng;
# tree pictures need Graphviz's dot.
DEMO_APT_PACKAGES := libusb-1.0-0 libgl1 libegl1 libx11-6 libgomp1 espeak-ng
TEST_APT_PACKAGES := $(DEMO_APT_PACKAGES) graphviz
DEMO_EXTRAS := voice
TEST_EXTRAS := test,robots,trials,voice,docs
DEMO_STAMP := $(VENV)/.bearchair-demo-installed
TEST_STAMP := $(VENV)/.bearchair-test-installed
DEMO_OUT ?= runs/demo
SEED ?= 0

.PHONY: demo test test-fast system-demo system-test install install-demo lint format bench tree docs clean

demo: install-demo
	$(BIN)/bearchair run --seed $(SEED) --out $(DEMO_OUT) --overwrite --mute; \
	status=$$?; echo "run record in $(DEMO_OUT) (inspect: $(BIN)/bearchair inspect $(DEMO_OUT))"; exit $$status

test: install
	$(BIN)/pytest -q

# The quick loop: the tests marked slow (physics-heavy) left out.
test-fast: install
	$(BIN)/pytest -q -m "not slow"

# Installs the Debian packages of $(1) that are missing: nothing, and no root, when all are there.
define apt_missing
	@if ! command -v dpkg-query >/dev/null 2>&1; then \
	  echo "not a Debian system: make sure these are installed: $(1) (docs/install.md)"; exit 0; \
	fi; \
	missing=""; for p in $(1); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "installing system packages:$$missing"; \
	  if [ "$$(id -u)" = 0 ]; then SUDO=""; \
	  elif command -v sudo >/dev/null 2>&1; then SUDO=sudo; \
	  else echo "missing system packages:$$missing; install them as root (apt-get install$$missing), or see docs/install.md for the pip-only path" >&2; exit 2; fi; \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	fi
endef

system-demo:
	$(call apt_missing,$(DEMO_APT_PACKAGES))

system-test:
	$(call apt_missing,$(TEST_APT_PACKAGES))

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip

$(DEMO_STAMP): pyproject.toml | $(BIN)/python
	$(MAKE) system-demo
	$(BIN)/python -m pip install -q -e ".[$(DEMO_EXTRAS)]"
	touch $(DEMO_STAMP)

# The example plug-in (its own distribution) is installed too: make test runs its tests.
PLUGIN := examples/bearchair-example-plugin

$(TEST_STAMP): pyproject.toml $(PLUGIN)/pyproject.toml | $(BIN)/python
	$(MAKE) system-test
	$(BIN)/python -m pip install -q -e ".[$(TEST_EXTRAS)]"
	$(BIN)/python -m pip install -q -e $(PLUGIN)
	touch $(TEST_STAMP) $(DEMO_STAMP)

install-demo: $(DEMO_STAMP)

install: $(TEST_STAMP)

lint: install
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/pyright

format: install
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

tree: install-demo
	$(BIN)/bearchair tree --format svg --blackboard --out mission.svg

docs: install
	$(BIN)/mkdocs build --strict --site-dir site

bench: install
	@for b in bench/*.py; do echo "== $$b"; $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) runs site .pytest_cache .ruff_cache *.egg-info
