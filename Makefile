# The two commands of the README: `make demo` (commission two emulated drives from examples/two_axes.pvl, then
# move them) and `make test`. Both create .venv on first use.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test bench venv clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -e '.[test]'
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	mkdir -p build
	$(BIN)/linmot-st motion examples/two_axes.pvl --axes 2 --drive-timings real --report build/report

test: $(STAMP)
	$(BIN)/pytest -q -n 2

bench: $(STAMP)
	$(BIN)/python -m linmot_st.bench

clean:
	rm -rf build .pytest_cache
