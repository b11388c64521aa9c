# Set-up and everyday commands.  Only python3 and make are assumed.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.inskit-installed
WARM := $(VENV)/.inskit-warm
# the compiled sources: an edit of any of them rebuilds the compile cache here, not in the next command
NUMBA_SRC := $(shell grep -rl numba src/inskit --include='*.py' 2>/dev/null)

.PHONY: run test bench install clean

$(BIN)/python:
	$(PY) tools/make_venv.py $(VENV)

$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/python -m pip install --disable-pip-version-check -q -e '.[test]'
	touch $(STAMP)

$(WARM): $(STAMP) $(NUMBA_SRC)
	@echo "building the compile cache and matplotlib's font cache (one run of the main job, output discarded)"
	$(BIN)/inskit navigate examples/drive_0708.toml --out $(VENV)/warm-up --force > /dev/null 2>&1 || \
	  $(BIN)/inskit navigate examples/drive_0708.toml --out $(VENV)/warm-up --force
	rm -rf $(VENV)/warm-up
	touch $(WARM)

install: $(WARM)

## run: install, then the main job on the bundled default data
run: install
	$(BIN)/inskit navigate examples/drive_0708.toml --force

## test: install, then the whole default test suite
test: install
	$(BIN)/python -m pytest -q

## bench: throughput figures as one JSON object
bench: install
	$(BIN)/inskit bench --json

clean:
	rm -rf $(VENV) build dist src/*.egg-info
