# Two entry points: `make demo` runs the mission in the simulated world, `make test` runs
# the tests. Both install what is missing first: Debian packages, a .venv, the project.

PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.bearchair-installed
# open3d needs libusb, libGL/EGL/X11 and libgomp; pyttsx3 speaks through espeak-ng;
# tree pictures need Graphviz's dot.
APT_PACKAGES := libusb-1.0-0 libgl1 libegl1 libx11-6 libgomp1 espeak-ng graphviz
DEMO_OUT ?= runs/demo
SEED ?= 0

.PHONY: demo test system install lint format bench tree clean

demo: install
	$(BIN)/bearchair run --seed $(SEED) --out $(DEMO_OUT) --mute; \
	status=$$?; echo "run record in $(DEMO_OUT) (inspect: $(BIN)/bearchair inspect $(DEMO_OUT))"; exit $$status

test: install
	$(BIN)/pytest -q

system:
	@missing=""; for p in $(APT_PACKAGES); do \
	  dpkg-query -W -f='$${Status}' $$p 2>/dev/null | grep -q "install ok installed" || missing="$$missing $$p"; \
	done; \
	if [ -n "$$missing" ]; then \
	  echo "installing system packages:$$missing"; \
	  SUDO=$$( [ "$$(id -u)" = 0 ] || echo sudo ); \
	  $$SUDO apt-get update -qq && DEBIAN_FRONTEND=noninteractive $$SUDO apt-get install -y -qq $$missing; \
	fi

# The example plug-in (its own distribution) is installed too: make test runs its tests.
PLUGIN := examples/bearchair-example-plugin

$(STAMP): pyproject.toml $(PLUGIN)/pyproject.toml
	$(MAKE) system
	test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[test,robots,trials,voice]"
	$(BIN)/python -m pip install -q -e $(PLUGIN)
	touch $(STAMP)

install: $(STAMP)

lint: install
	$(BIN)/ruff check .
	$(BIN)/ruff format --check .
	$(BIN)/pyright

format: install
	$(BIN)/ruff check --fix .
	$(BIN)/ruff format .

tree: install
	$(BIN)/bearchair tree --format svg --blackboard --out mission.svg

bench: install
	@for b in bench/*.py; do echo "== $$b"; $(BIN)/python $$b || exit 1; done

clean:
	rm -rf $(VENV) runs .pytest_cache .ruff_cache *.egg-info
