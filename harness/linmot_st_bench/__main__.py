"""`python -m linmot_st_bench [AREA...]`: the same as `make bench` / `linmot-st bench`."""

import sys

from linmot_st_bench.runner import main

sys.exit(main())
