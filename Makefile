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
	@echo "building the compile cache of every command and matplotlib's font cache (each command once on small inputs, outputs discarded)"
	@# byte-code of inskit's modules, written here once: with PYTHONDONTWRITEBYTECODE set, every command
	@# would otherwise compile some thirty modules from source at its start (~60 ms)
	$(BIN)/python -m compileall -q src/inskit
	$(BIN)/python -m inskit.jobs.compile_cache || \
	  echo "warning: a warm-up command failed (above); the commands it stands for compile at their first run"
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
