/* The shared glue of every built PLC library (docs/architecture.md 1.2, 1.3).
 *
 * Both backends generate C that provides MatIEC's runtime contract (config_init__, config_run__,
 * common_ticktime__) plus the tables plc_root_addr/plc_type_size. This file adds the rest: the virtual
 * clock __CURRENT_TIME, the scan loop in C, and PLC fault capture.
 *
 * It includes no MatIEC header on purpose: the builtin backend must build where MatIEC is absent.
 * IEC_TIME's layout ({long tv_sec; long tv_nsec;}) is restated here.
 *
 * Faults. The builtin backend checks divisions and indices itself and calls plc_raise_fault(). C compiled
 * by iec2c does not: there an integer division by zero raises SIGFPE and an index out of range traps
 * (the backend compiles it with UBSan's bounds, shift-exponent and float-cast-overflow checks, whose entry
 * points are defined below; with a compiler that only has a trapping bounds check: SIGILL). The
 * handlers below turn such a
 * signal, raised by this thread inside plc_step/plc_init, into a siglongjmp back to the loop. A signal
 * raised anywhere else is passed on to the handler that was installed before ours (pytest's
 * faulthandler, Python's default, or another PLC instance's glue).
 *
 * Scan watchdog. A scan that never ends (WHILE TRUE DO ... END_WHILE) would hold the process forever, as
 * a real PLC runtime's task watchdog prevents. While plc_step runs, a POSIX timer on the CPU clock of the
 * calling thread ticks every limit / WD_TICKS (a real-time signal sent to that thread, identified by its
 * value, so that several PLC instances and other users of the signal do not mix); a tick that finds the
 * scan count unchanged for WD_TICKS ticks ends the scan like a fault: kind 5, located at the interrupted
 * instruction. The CPU clock, not the wall clock: a loaded machine does not trip it, a spinning scan
 * does. The limit is per scan and 0 turns it off (plc_set_watchdog_ns).
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <pthread.h>
#include <setjmp.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/syscall.h>
#include <time.h>
#include <ucontext.h>
#include <unistd.h>

#define PLC_ABI_VERSION 3
#define WD_TICKS 4

typedef struct { long tv_sec; long tv_nsec; } plc_iec_time_t;   /* MatIEC's IEC_TIME */

/* provided by the generated C */
extern void config_init__(void);
extern void config_run__(unsigned long tick);
extern unsigned long long common_ticktime__;

/* read by every TON/TOF/TP of the generated code; advanced after each scan */
plc_iec_time_t __CURRENT_TIME;

static unsigned long plc_tick;
static unsigned long long plc_now_ns;
static unsigned long long plc_scans;

static int fault_kind;
static char fault_pou[128];
static char fault_file[256];
static int fault_line;
static unsigned long fault_pc;

/* the scan in progress, if any; guarded by the thread that runs it */
static volatile sig_atomic_t in_scan;
static pthread_t scan_thread;
static sigjmp_buf scan_jmp;

#define N_SIGNALS 4
static const int caught_signals[N_SIGNALS] = {SIGFPE, SIGILL, SIGSEGV, SIGBUS};
static struct sigaction previous[N_SIGNALS];
static int handlers_installed;

/* the scan watchdog */
static unsigned long long watchdog_ns = 1000000000ULL;   /* CPU time per scan; 0 = off */
static int wd_signal;                                   /* SIGRTMIN + 4 (SIGRTMIN is not a constant) */
static struct sigaction wd_previous;
static timer_t wd_timer;
static int wd_timer_ok;
static pid_t wd_tid;                                    /* the thread whose CPU clock the timer follows */
static int wd_token;                                    /* its address tells our timer's signal */
static volatile unsigned long long wd_seen;
static volatile int wd_stuck;

__attribute__((visibility("default"))) int plc_abi_version(void) { return PLC_ABI_VERSION; }

static void set_clock(unsigned long long t)
{
    plc_now_ns = t;
    __CURRENT_TIME.tv_sec = (long)(t / 1000000000ULL);
    __CURRENT_TIME.tv_nsec = (long)(t % 1000000000ULL);
}

static void copy_str(char *dst, size_t size, const char *src)
{
    size_t i = 0;
    if (src)
        for (; src[i] && i + 1 < size; i++) dst[i] = src[i];
    dst[i] = '\0';
}

static void upper_case(char *s)
{
    for (; *s; s++)
        if (*s >= 'a' && *s <= 'z') *s = (char)(*s - 'a' + 'A');
}

static void clear_fault(void)
{
    fault_kind = 0;
    fault_pou[0] = fault_file[0] = '\0';
    fault_line = 0;
    fault_pc = 0;
}

/* A POU name from the symbol that holds pc: MatIEC names FB and program bodies <POU>_body__,
 * FB initialisers <POU>_init__ and FUNCTIONs after the POU itself. The loader refines this from debug
 * information where it can (an inlined body has no symbol of its own). */
static void locate_pc(unsigned long pc)
{
    Dl_info info;
    if (!pc || !dladdr((void *)pc, &info)) return;
    fault_pc = pc - (unsigned long)info.dli_fbase;
    if (!info.dli_sname) return;
    copy_str(fault_pou, sizeof fault_pou, info.dli_sname);
    char *suffix = strstr(fault_pou, "_body__");
    if (!suffix) suffix = strstr(fault_pou, "_init__");
    if (suffix) *suffix = '\0';
    upper_case(fault_pou);
}

static unsigned long context_pc(void *ctx)
{
    ucontext_t *uc = (ucontext_t *)ctx;
    if (!uc) return 0;
#if defined(__x86_64__)
    return (unsigned long)uc->uc_mcontext.gregs[REG_RIP];
#elif defined(__i386__)
    return (unsigned long)uc->uc_mcontext.gregs[REG_EIP];
#elif defined(__aarch64__)
    return (unsigned long)uc->uc_mcontext.pc;
#else
    return 0;
#endif
}

static int kind_of(int sig, const siginfo_t *info)
{
    switch (sig) {
    /* integer division by zero, and MIN / -1 (x86 reports both as FPE_INTDIV; other CPUs say FPE_INTOVF) */
    case SIGFPE: return (info && (info->si_code == FPE_INTDIV || info->si_code == FPE_INTOVF)) ? 1 : 3;
    case SIGILL: return 2;   /* the trapping bounds sanitizer: the only source of SIGILL in PLC code */
    default: return 4;
    }
}

static void chain(int index, int sig, siginfo_t *info, void *ctx)
{
    struct sigaction *prev = &previous[index];
    if (prev->sa_flags & SA_SIGINFO) {
        if (prev->sa_sigaction) { prev->sa_sigaction(sig, info, ctx); return; }
    } else if (prev->sa_handler != SIG_DFL && prev->sa_handler != SIG_IGN) {
        prev->sa_handler(sig);
        return;
    }
    /* default action: give the signal back to it; the faulting instruction runs again and ends the
     * process as it would have without us (a fault is not ignorable) */
    sigaction(sig, prev, NULL);
    if (info && info->si_code <= 0) raise(sig);   /* sent by kill(), not a fault: re-send it */
}

static void on_watchdog(int sig, siginfo_t *info, void *ctx)
{
    if (info && info->si_code == SI_TIMER && info->si_value.sival_ptr == (void *)&wd_token) {
        if (!in_scan || !pthread_equal(pthread_self(), scan_thread)) return;   /* a tick between scans */
        if (plc_scans != wd_seen) {
            wd_seen = plc_scans;
            wd_stuck = 0;
            return;
        }
        if (++wd_stuck < WD_TICKS) return;
        fault_kind = 5;
        locate_pc(context_pc(ctx));
        in_scan = 0;
        siglongjmp(scan_jmp, 1);
    }
    /* another instance's timer, or another user of the signal: pass it on; never to the default action
       (it would end the process) */
    if (wd_previous.sa_flags & SA_SIGINFO) {
        if (wd_previous.sa_sigaction) wd_previous.sa_sigaction(sig, info, ctx);
    } else if (wd_previous.sa_handler != SIG_DFL && wd_previous.sa_handler != SIG_IGN) {
        wd_previous.sa_handler(sig);
    }
}

static void on_signal(int sig, siginfo_t *info, void *ctx)
{
    int index = 0;
    while (index < N_SIGNALS && caught_signals[index] != sig) index++;
    if (in_scan && pthread_equal(pthread_self(), scan_thread) && info && info->si_code > 0) {
        fault_kind = kind_of(sig, info);
        locate_pc(context_pc(ctx));
        in_scan = 0;
        siglongjmp(scan_jmp, 1);
    }
    if (index < N_SIGNALS) chain(index, sig, info, ctx);
}

static void install_handlers(void)
{
    if (handlers_installed) return;
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_sigaction = on_signal;
    sa.sa_flags = SA_SIGINFO | SA_NODEFER | SA_ONSTACK;
    sigemptyset(&sa.sa_mask);
    for (int i = 0; i < N_SIGNALS; i++) sigaction(caught_signals[i], &sa, &previous[i]);
    wd_signal = SIGRTMIN + 4;
    sa.sa_sigaction = on_watchdog;
    sigaction(wd_signal, &sa, &wd_previous);
    handlers_installed = 1;
}

/* the watchdog timer of the calling thread's CPU clock, created on first use (again for another thread) */
static int watchdog_timer(void)
{
    pid_t tid = (pid_t)syscall(SYS_gettid);
    if (wd_timer_ok && wd_tid == tid) return 1;
    if (wd_timer_ok) {
        timer_delete(wd_timer);
        wd_timer_ok = 0;
    }
    struct sigevent sev;
    memset(&sev, 0, sizeof sev);
    sev.sigev_notify = SIGEV_THREAD_ID;
#ifdef sigev_notify_thread_id
    sev.sigev_notify_thread_id = tid;
#else
    sev._sigev_un._tid = tid;
#endif
    sev.sigev_signo = wd_signal;
    sev.sigev_value.sival_ptr = (void *)&wd_token;
    if (timer_create(CLOCK_THREAD_CPUTIME_ID, &sev, &wd_timer) != 0) return 0;
    wd_timer_ok = 1;
    wd_tid = tid;
    return 1;
}

static void watchdog_arm(int on)
{
    struct itimerspec its;
    memset(&its, 0, sizeof its);
    if (on) {
        unsigned long long tick = watchdog_ns / WD_TICKS;
        if (tick < 1000000ULL) tick = 1000000ULL;        /* at most a tick per ms of CPU */
        its.it_value.tv_sec = its.it_interval.tv_sec = (time_t)(tick / 1000000000ULL);
        its.it_value.tv_nsec = its.it_interval.tv_nsec = (long)(tick % 1000000000ULL);
        wd_seen = plc_scans;
        wd_stuck = 0;
    }
    timer_settime(wd_timer, 0, &its, NULL);
}

__attribute__((visibility("default"))) void plc_set_watchdog_ns(unsigned long long ns) { watchdog_ns = ns; }
__attribute__((visibility("default"))) unsigned long long plc_watchdog_ns(void) { return watchdog_ns; }

/* UBSan's entry points for the checks compiled into iec2c's C (toolchain/cc.py check_flags, with
 * -fno-sanitize-recover: the _abort variants). Each ends the scan as a PLC fault of its own kind located
 * at its caller: the loader finds the POU and the ST line in the library's line table (iec2c -O l), since
 * the check itself sits in MatIEC's headers. The data they get (source location, types) is not used.
 * Hidden: bound inside this library at link time, so neither another PLC library nor a libubsan loaded
 * into the process can take the calls. */
static void ubsan_fault(int kind, void *ret) __attribute__((noreturn));
static void ubsan_fault(int kind, void *ret)
{
    if (!(in_scan && pthread_equal(pthread_self(), scan_thread))) abort();
    fault_kind = kind;
    locate_pc((unsigned long)ret - 1);   /* inside the call, not after it */
    in_scan = 0;
    siglongjmp(scan_jmp, 1);
}

__attribute__((visibility("hidden"), noreturn)) void __ubsan_handle_out_of_bounds_abort(void *data, void *index)
{
    (void)data; (void)index;
    ubsan_fault(2, __builtin_return_address(0));
}

__attribute__((visibility("hidden"), noreturn))
void __ubsan_handle_shift_out_of_bounds_abort(void *data, void *lhs, void *rhs)
{
    (void)data; (void)lhs; (void)rhs;
    ubsan_fault(6, __builtin_return_address(0));
}

__attribute__((visibility("hidden"), noreturn)) void __ubsan_handle_float_cast_overflow_abort(void *data, void *from)
{
    (void)data; (void)from;
    ubsan_fault(7, __builtin_return_address(0));
}

/* Called by code of the builtin backend at a checked fault; does not return. Outside a scan (which
 * cannot happen for generated code) it records the fault and returns to nothing: abort is the only
 * honest choice. */
__attribute__((visibility("default"), noreturn))
void plc_raise_fault(int kind, const char *pou, const char *file, int line)
{
    fault_kind = kind ? kind : 3;
    copy_str(fault_pou, sizeof fault_pou, pou);
    upper_case(fault_pou);
    copy_str(fault_file, sizeof fault_file, file);
    fault_line = line;
    fault_pc = 0;
    if (in_scan && pthread_equal(pthread_self(), scan_thread)) {
        in_scan = 0;
        siglongjmp(scan_jmp, 1);
    }
    abort();
}

__attribute__((visibility("default"))) void plc_init(void)
{
    install_handlers();
    clear_fault();
    plc_tick = 0;
    plc_scans = 0;
    set_clock(0);
    scan_thread = pthread_self();
    if (sigsetjmp(scan_jmp, 1) == 0) {
        in_scan = 1;
        config_init__();
    }
    in_scan = 0;
}

/* What ends a run of idle scans early (plc_step_idle); NULL for plain scans (plc_step). */
typedef struct {
    unsigned long long until_ns;      /* no scan starts at or after this PLC time */
    short *rx_count;                  /* the mailbox's RxCount (INT): 0 before each scan */
    const short *tx_count;            /* the mailbox's TxCount (INT): the run ends after a scan that sets it */
    unsigned char *const *watch;      /* byte ranges whose change ends the run after the scan that made it */
    const unsigned long *watch_size;
    int n_watch;
    unsigned char *shadow;            /* their bytes before the scan, back to back */
} idle_stop_t;

static int watched_changed(const idle_stop_t *idle)
{
    const unsigned char *s = idle->shadow;
    for (int i = 0; i < idle->n_watch; s += idle->watch_size[i], i++)
        if (memcmp(idle->watch[i], s, idle->watch_size[i]) != 0) return 1;
    return 0;
}

static void take_snapshot(const idle_stop_t *idle)
{
    unsigned char *s = idle->shadow;
    for (int i = 0; i < idle->n_watch; s += idle->watch_size[i], i++) memcpy(s, idle->watch[i], idle->watch_size[i]);
}

static unsigned long run_scans(unsigned long n, const idle_stop_t *idle)
{
    /* Globals are in memory at every call of config_run__, so after a siglongjmp plc_scans tells how
     * many scans completed; start is not modified after sigsetjmp, so it keeps its value. */
    const unsigned long long start = plc_scans;
    if (fault_kind) return 0;   /* a faulted PLC stays stopped until plc_init */
    scan_thread = pthread_self();
    install_handlers();
    const int watched = watchdog_ns && watchdog_timer();
    if (watched) watchdog_arm(1);
    if (idle && idle->n_watch) take_snapshot(idle);
    if (sigsetjmp(scan_jmp, 1) == 0) {
        in_scan = 1;
        const long tick_ns = (long)common_ticktime__;
        for (unsigned long i = 0; i < n; i++) {
            if (idle) {
                if (plc_now_ns >= idle->until_ns) break;
                *idle->rx_count = 0;          /* what the harness writes before a scan that receives nothing */
            }
            config_run__(plc_tick++);
            plc_scans++;
            /* the clock advances incrementally: no 64-bit division per scan */
            plc_now_ns += (unsigned long long)tick_ns;
            __CURRENT_TIME.tv_nsec += tick_ns;
            while (__CURRENT_TIME.tv_nsec >= 1000000000L) {
                __CURRENT_TIME.tv_nsec -= 1000000000L;
                __CURRENT_TIME.tv_sec++;
            }
            if (idle && (*idle->tx_count || (idle->n_watch && watched_changed(idle)))) break;
        }
    }
    in_scan = 0;
    if (watched) watchdog_arm(0);
    return (unsigned long)(plc_scans - start);
}

__attribute__((visibility("default"))) unsigned long plc_step(unsigned long n) { return run_scans(n, NULL); }

/* Idle scans (docs/plc-integration.md, "Idle scans"): up to n scans with an empty Rx, as the harness runs
 * them while no frame reaches the PLC. The run ends before a scan that would start at or after until_ns
 * (the next bus event), after the scan that put a frame into Tx, after a scan that changed a watched byte
 * range (what the caller samples between scans), or at a fault. Returns the scans run; fewer than n
 * without a fault is an ordinary end, the caller tells them apart by plc_fault_kind. */
__attribute__((visibility("default")))
unsigned long plc_step_idle(unsigned long n, unsigned long long until_ns, short *rx_count, const short *tx_count,
                            unsigned char *const *watch, const unsigned long *watch_size, int n_watch,
                            unsigned char *shadow)
{
    const idle_stop_t idle = {until_ns, rx_count, tx_count, watch, watch_size, n_watch, shadow};
    return run_scans(n, &idle);
}

__attribute__((visibility("default"))) int plc_fault_kind(void) { return fault_kind; }
__attribute__((visibility("default"))) const char *plc_fault_pou(void) { return fault_pou; }
__attribute__((visibility("default"))) const char *plc_fault_file(void) { return fault_file; }
__attribute__((visibility("default"))) int plc_fault_line(void) { return fault_line; }
__attribute__((visibility("default"))) unsigned long plc_fault_pc(void) { return fault_pc; }
__attribute__((visibility("default"))) unsigned long long plc_time_ns(void) { return plc_now_ns; }
__attribute__((visibility("default"))) void plc_set_time_ns(unsigned long long t) { set_clock(t); }
__attribute__((visibility("default"))) unsigned long long plc_tick_ns(void) { return common_ticktime__; }
__attribute__((visibility("default"))) unsigned long long plc_scan_count(void) { return plc_scans; }
