/* Linked into coverage builds only (docs/coverage.md). libgcov's counters of this library are its own
   (each private copy a Plc loads has them): plc_coverage_dump writes them out, merged by libgcov into
   the .gcda files under $GCOV_PREFIX, and zeroes them, so the next dump adds only what ran since. */
extern void __gcov_dump(void);
extern void __gcov_reset(void);

void plc_coverage_dump(void)
{
    __gcov_dump();
    __gcov_reset();
}
