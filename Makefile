# The two commands of the README: `make demo` (commission two emulated drives from examples/two_axes.pvl, then
# move them) and `make test`. Both create .venv on first use.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: demo test lint st-coverage bench venv clean

# st_lib's coverage comes from the tests of st_lib (a subset: coverage builds of the whole suite would
# compile every test's program again for little more of st_lib; docs/coverage.md)
ST_COVERAGE_TESTS := tests/st_lib/test_stlib_*.py tests/st_lib/test_plcopen.py tests/st_lib/motion/test_stlib_*.py \
                     tests/st_lib/motion/test_motion_fbs.py tests/st_lib/motion/test_motion_budget.py \
                     tests/st_lib/commission/test_commission_st.py

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip
	$(BIN)/pip install -q -e '.[test]'
	touch $(STAMP)

venv: $(STAMP)

demo: $(STAMP)
	mkdir -p build
	$(BIN)/linmot-st motion examples/two_axes.pvl --axes 2 --drive-timings real --report build/report

# lint first (seconds), then st_lib's coverage, so that the whole suite's summary is the last line CI reads
test: $(STAMP)
	$(MAKE) lint
	$(MAKE) st-coverage
	$(BIN)/pytest -q -n 2

# ruff (pyproject [tool.ruff]) over the whole tree; mypy over the modules with a typed contract ([tool.mypy])
lint: $(STAMP)
	$(BIN)/ruff check .
	$(BIN)/mypy
	$(BIN)/lint-imports --no-cache     # the layers of docs/architecture.md (pyproject.toml [tool.importlinter])

# st_lib's line and branch coverage: the table per file, build/st-coverage/{coverage.xml,html/index.html}
st-coverage: $(STAMP)
	$(BIN)/pytest -q -n 2 -p no:cacheprovider --linmot-cov --linmot-cov-dir build/st-coverage \
	  -o linmot_st_cov_pous=false $(ST_COVERAGE_TESTS)

bench: $(STAMP)
	$(BIN)/python -m linmot_st_bench

clean:
	rm -rf build .pytest_cache
