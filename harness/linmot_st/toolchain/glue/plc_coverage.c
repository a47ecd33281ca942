/* Linked into coverage builds only (docs/coverage.md). libgcov's counters of this library are its own
   (each private copy a Plc loads has them): plc_coverage_dump writes them out once, added by libgcov to
   the .gcda files under $GCOV_PREFIX; libgcov then skips its own write at exit (that would go to the
   folder gcc compiled in). */
extern void __gcov_dump(void);

void plc_coverage_dump(void)
{
    __gcov_dump();
}
