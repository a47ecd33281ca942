"""The benchmarks of linmot-st (`make bench`, `linmot-st bench`, `python -m linmot_st_bench [AREA...]`).

Development code, kept out of the wheel (pyproject.toml excludes this package): the benches measure the
whole stack from above (a bus bench builds and runs a PLC, a toolchain bench commissions a big dataset),
so they sit above every layer of linmot_st and nothing in linmot_st imports them. They run from a
checkout (an editable install puts harness/ on the path); runner.py runs the areas and prints the table.
"""
