/*
 * A minimal FMI 2.0 and FMI 3.0 host for the BeamBody FMU, used as a test fixture by
 * tests/python/hosts/test_c_host.py (which compiles it with the system's cc and runs it natively and
 * under valgrind) and tests/python/hosts/test_c_host_platforms.py (which cross-compiles it for Windows
 * with mingw-w64 and for Linux aarch64, and runs it under wine and qemu-aarch64). It loads the
 * unzipped FMU's library for the platform it was compiled for (binaries/win64/BeamBody.dll,
 * binaries/aarch64-linux/BeamBody.so, binaries/darwin64/BeamBody.dylib, else
 * binaries/linux64/BeamBody.so; with --fmi3 FMI 3.0's folders: binaries/x86_64-windows/,
 * binaries/aarch64-linux/, binaries/x86_64-darwin/ or binaries/aarch64-darwin/, else
 * binaries/x86_64-linux/) with dlopen/dlsym or LoadLibraryA/GetProcAddress, as a real host
 * would, and runs these checks:
 *
 *   1. scene:   the paper's scene (default parameters, phi_source = law, t = 0 .. 10.2 s,
 *               communication step 0.01 s, tolerance undefined = the FMU's default) recording
 *               v1, theta1, u2 at every communication point; all must be finite. A summary goes
 *               to stdout and, with -o, the whole trajectory as CSV: t, v1, theta1, u2 as %.17g
 *               (round-trips exactly), then the IEEE-754 bits of v1, theta1, u2 as 16 hex digits
 *               (exact whatever the C library's printf does), one row per communication point.
 *   2. cycles:  N fmi2Instantiate/fmi2FreeInstance cycles, most also doing a part of the life
 *               cycle (set-up, a few steps, FMU states and their serialization, reset, calls
 *               out of sequence, rejected instantiations), every status checked.
 *   3. threads: K instances (each with its own phi_end and EI) created, stepped over the paper's
 *               scene and freed in K concurrent threads; the trajectories must be bit-identical
 *               to the same K configurations run one after another in the main thread.
 *   4. exchange: the paper's scene under Model Exchange, integrated by this host itself with the
 *               classical Runge-Kutta method at a fixed step of 0.5 ms, through the FMU's time
 *               event at the law's end (the event iteration, then continuous-time mode again),
 *               with fmi2CompletedIntegratorStep and the event indicators at every step; v1,
 *               theta1, u2 at every communication point (with --me-out, a CSV as -o's). The FMU
 *               state taken at t = 5.1 s, serialized and restored into a second instance, must
 *               continue bit for bit; calls out of Model Exchange's sequence are refused.
 *
 * With --fmi3 the unzipped FMU is the FMI 3.0 archive (BeamBody-fmi3.fmu: its modelDescription
 * gives the instantiationToken and the value references of <Float64>, <Enumeration>, ...
 * variables), all 75 fmi3* functions must be exported (and the 44 fmi2* ones: the library has
 * both), and checks 1-4 run through FMI 3.0: the same code, calling the FMI 3.0 functions through
 * adapters with FMI 2.0's signatures (section "FMI 3.0 behind FMI 2.0's signatures"), which also
 * check what FMI 3.0 returns in out-arguments: fmi3DoStep's (no event handling needed, no early
 * return, not terminated, lastSuccessfulTime = tc + h exactly) and fmi3UpdateDiscreteStates's six.
 * The experiment's set-up goes with fmi3EnterInitializationMode, enumerations are set with
 * fmi3SetInt64, fmi2LastSuccessfulTime is the independent variable `time`, an fmi2Type that is
 * neither interface becomes fmi3InstantiateScheduledExecution (which this FMU refuses). Then two
 * checks of FMI 3.0 alone:
 *   5. intermediate: phi_source = input, requiredIntermediateVariables = {phi}, intermediate_step
 *               = 1 ms, communication step 8.5 ms over t = 0 .. 1.7 s: the FMU calls the host's
 *               intermediate-update callback between the parts of each step (intermediate_step
 *               while more than 1.25 of it remains, then the rest: 8 callbacks a step), where the
 *               host sets phi to the paper's law at the time it is given, computed here with the
 *               C library's sin. The count and the times of the callbacks must be the rule's
 *               exactly, `time` must read the callback's time, and v1 must stay within 1e-5 m of
 *               the law's run (phi_source = law, same steps, all three runs at tolerance 1e-8;
 *               the FMU's sin is its own) and closer to it than a run given phi at the
 *               communication points only (measured 2.2e-6 m against 2.4e-4 m).
 *   6. misuse:  calls that must return fmi3Error without crashing: a NULL instance; an FMI 2.0
 *               instance passed to fmi3DoStep and an FMI 3.0 one to fmi2DoStep (both still usable
 *               after, and equal after a step); fmi3InstantiateScheduledExecution (NULL);
 *               in configuration mode a parameter that is not structural, and leaving it twice;
 *               fmi3UpdateDiscreteStates in co-simulation; fmi3DoStep with a NULL out-argument.
 *               Each refusal logs exactly one error (none for NULL).
 *   7. arrays:  n_elements = 4 set in configuration mode; co-simulation with the law, 100 steps
 *               of 8.5 ms: nodal_v read with nValues = 4 after each (never past the array), its
 *               last element v1 bit for bit; nValues = 3 refused. Model Exchange with
 *               n_elements = 2: 8 continuous states, finite derivatives.
 *
 * usage: host UNZIPDIR [--fmi3] [--cycles N] [--threads K] [-o TRAJ.csv] [--me-out TRAJ.csv]
 *                     [--so LIB] [--save-state S STATE.bin] [--resume STATE.bin]
 *                     [--no-dlclose | --reloads R]
 *        host UNZIPDIR --bench-dostep ROUNDS [--feed FEED] [--h H]
 * --so loads another build of the library (with the unzipped FMU's modelDescription.xml);
 * --cycles 0 and --threads 0 skip checks 2 and 3.
 * --save-state S FILE: in the scene (check 1), after communication step S (t = S*h, once its
 * outputs are recorded) the state is taken with fmi2GetFMUstate, written to FILE as the raw bytes
 * of fmi2SerializeFMUstate, and freed; the scene then continues (its trajectory is unchanged).
 * --resume FILE: the scene instantiates and initializes as usual, then restores the state of
 * FILE (fmi2DeSerializeFMUstate, fmi2SetFMUstate); its step S comes from fmi2LastSuccessfulTime
 * (which must be a communication point), and the scene continues from step S to the end, so -o
 * then writes the points S .. 1020 only. Both options only change check 1; they compose with
 * each other and with checks 2 and 3.
 * --no-dlclose keeps the library loaded at exit; --reloads R then loads, uses (one plain and one
 * FMU-state cycle) and unloads it R more times.
 * --bench-dostep ROUNDS replaces the checks by the benchmark of fmi2DoStep (section 4, run by
 * `cargo xtask bench`); --feed FEED runs one way of sending phi only, --h H one communication step
 * only (for a profiler: `valgrind --tool=callgrind` counts its instructions). FMI 2.0 only.
 * Exit code: 0 when every check passed, 1 on a failure (with a message on stderr), 2 on bad usage.
 *
 * What differs between POSIX and Windows (loading the library and its error text, threads and
 * their start gate, the monotonic clock) is in the platform shim below; the rest is plain C11.
 * The FMI 2.0 and 3.0 types are written here from the standard's headers (fmi2TypesPlatform.h,
 * fmi2FunctionTypes.h, fmi3PlatformTypes.h, fmi3FunctionTypes.h) so that the fixture needs
 * nothing beyond the C library, the system's thread and loader API (pthread and dlfcn, or
 * kernel32) and libm.
 */

/* ----- platform shim ------------------------------------------------------------------------ */

/* Feature macros come before any system header. */
#ifdef _WIN32
/* mingw-w64's own C99 printf (%zu, %lld, %a, correctly rounded %.17g) instead of msvcrt's */
#define __USE_MINGW_ANSI_STDIO 1
#define WIN32_LEAN_AND_MEAN
#ifndef _WIN32_WINNT
#define _WIN32_WINNT 0x0601 /* Windows 7: condition variables */
#endif
#include <windows.h>
#else
#ifdef __APPLE__
#define _DARWIN_C_SOURCE /* RTLD_NOLOAD */
#endif
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <pthread.h>
#endif

#include <math.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* The FMU's library in an unzipped FMU, by the platform this host is compiled for (the FMI
 * 2.0.4 platform tuples; aarch64-linux is the form 2.0.4 allows for platforms beyond the
 * original five). */
#if defined(_WIN64)
#define LIB_DEFAULT "binaries/win64/BeamBody.dll"
#elif defined(_WIN32)
#define LIB_DEFAULT "binaries/win32/BeamBody.dll"
#elif defined(__APPLE__)
#define LIB_DEFAULT "binaries/darwin64/BeamBody.dylib"
#elif defined(__linux__) && defined(__aarch64__)
#define LIB_DEFAULT "binaries/aarch64-linux/BeamBody.so"
#else
#define LIB_DEFAULT "binaries/linux64/BeamBody.so"
#endif

/* The same in an unzipped FMI 3.0 FMU (its platform tuples). */
#if defined(_WIN64)
#define LIB_DEFAULT3 "binaries/x86_64-windows/BeamBody.dll"
#elif defined(_WIN32)
#define LIB_DEFAULT3 "binaries/x86-windows/BeamBody.dll"
#elif defined(__APPLE__) && defined(__aarch64__)
#define LIB_DEFAULT3 "binaries/aarch64-darwin/BeamBody.dylib"
#elif defined(__APPLE__)
#define LIB_DEFAULT3 "binaries/x86_64-darwin/BeamBody.dylib"
#elif defined(__linux__) && defined(__aarch64__)
#define LIB_DEFAULT3 "binaries/aarch64-linux/BeamBody.so"
#else
#define LIB_DEFAULT3 "binaries/x86_64-linux/BeamBody.so"
#endif

/* printf-style checking of our own formatting functions: on mingw-w64 with its C99 stdio the
 * archetype is gnu_printf (plain `printf` would mean msvcrt's, which knows no %zu). */
#ifdef __MINGW_PRINTF_FORMAT
#define PRINTF_LIKE(fmt, first) __attribute__((format(__MINGW_PRINTF_FORMAT, fmt, first)))
#else
#define PRINTF_LIKE(fmt, first) __attribute__((format(printf, fmt, first)))
#endif

/* A symbol of the library as a generic function pointer; SYM below converts it to the
 * function's type (a conversion between function pointer types, which ISO C allows). */
typedef void (*LibFn)(void);

#ifdef _WIN32

typedef HMODULE Lib;

/* The text of GetLastError(); one buffer, used by the main thread only. */
static const char *lib_error(void) {
    static char text[512];
    DWORD code = GetLastError();
    int n = snprintf(text, sizeof text, "Windows error %lu: ", (unsigned long)code);
    DWORD got = FormatMessageA(FORMAT_MESSAGE_FROM_SYSTEM | FORMAT_MESSAGE_IGNORE_INSERTS, NULL,
                               code, 0, text + n, (DWORD)(sizeof text - (size_t)n), NULL);
    while (got > 0 && (text[n + got - 1] == '\n' || text[n + got - 1] == '\r')) got--;
    text[n + got] = '\0';
    return text;
}

/* Windows paths: the FMU path is built with '/', which LoadLibraryA's documentation asks not
 * to use (and which GetModuleHandleA would not match). */
static void win_path(char *dst, size_t cap, const char *src) {
    snprintf(dst, cap, "%s", src);
    for (char *p = dst; *p; p++)
        if (*p == '/') *p = '\\';
}

static Lib lib_open(const char *path) {
    char p[4096];
    win_path(p, sizeof p, path);
    return LoadLibraryA(p);
}

static LibFn lib_sym(Lib lib, const char *name) {
    /* FARPROC to void (*)(void): the generic function pointer, no -Wcast-function-type */
    return (LibFn)(void (*)(void))GetProcAddress(lib, name);
}

static int lib_close(Lib lib) { return FreeLibrary(lib) ? 0 : -1; }

/* Whether the library is still mapped (after lib_close); does not load it or count a use. */
static int lib_loaded(const char *path) {
    char p[4096];
    win_path(p, sizeof p, path);
    return GetModuleHandleA(p) != NULL;
}

/* No message boxes: a DLL that does not load, or a crash, must end the process with a status
 * that the test sees (under wine, a crash would otherwise start winedbg). */
static void platform_init(void) {
    SetErrorMode(SEM_FAILCRITICALERRORS | SEM_NOGPFAULTERRORBOX | SEM_NOOPENFILEERRORBOX);
}

/* Windows threads, not winpthreads: host.exe then needs no mingw runtime DLL, and the FMU sees
 * the threads a native Windows host (MSVC-built, using CreateThread or std::thread) creates. */
typedef HANDLE Thread;
typedef DWORD ThreadResult;
#define THREAD_CALL WINAPI
static int thread_start(Thread *t, ThreadResult(THREAD_CALL *fn)(void *), void *arg) {
    *t = CreateThread(NULL, 0, fn, arg, 0, NULL);
    return *t ? 0 : -1;
}
static void thread_join(Thread t) {
    WaitForSingleObject(t, INFINITE);
    CloseHandle(t);
}

/* A one-shot start gate for n threads (what pthread_barrier_wait does once). */
typedef struct {
    CRITICAL_SECTION lock;
    CONDITION_VARIABLE all_in;
    unsigned n, arrived;
} Gate;
static int gate_init(Gate *g, unsigned n) {
    InitializeCriticalSection(&g->lock);
    InitializeConditionVariable(&g->all_in);
    g->n = n;
    g->arrived = 0;
    return 0;
}
static void gate_wait(Gate *g) {
    EnterCriticalSection(&g->lock);
    if (++g->arrived == g->n) WakeAllConditionVariable(&g->all_in);
    while (g->arrived < g->n) SleepConditionVariableCS(&g->all_in, &g->lock, INFINITE);
    LeaveCriticalSection(&g->lock);
}
static void gate_destroy(Gate *g) { DeleteCriticalSection(&g->lock); }

/* seconds on a monotonic clock */
static double now(void) {
    LARGE_INTEGER f, c;
    QueryPerformanceFrequency(&f);
    QueryPerformanceCounter(&c);
    return (double)c.QuadPart / (double)f.QuadPart;
}

#else /* POSIX */

typedef void *Lib;

static const char *lib_error(void) {
    const char *e = dlerror();
    return e ? e : "(no dlerror)";
}

/* RTLD_LOCAL: the FMU's symbols must not leak into the global namespace (several FMUs export
 * the same fmi2* names); RTLD_NOW: a missing dependency fails here, not mid-run. */
static Lib lib_open(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }

static LibFn lib_sym(Lib lib, const char *name) {
    /* dlsym returns void *, which POSIX (not ISO C) allows to convert to a function pointer. */
    return (LibFn)dlsym(lib, name);
}

static int lib_close(Lib lib) { return dlclose(lib) ? -1 : 0; }

/* RTLD_NOLOAD: a handle only if the library is still mapped, without loading it. */
static int lib_loaded(const char *path) {
    void *still = dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_NOLOAD);
    if (still) dlclose(still);
    return still != NULL;
}

static void platform_init(void) {}

typedef pthread_t Thread;
typedef void *ThreadResult;
#define THREAD_CALL
static int thread_start(Thread *t, ThreadResult (*fn)(void *), void *arg) {
    return pthread_create(t, NULL, fn, arg) ? -1 : 0;
}
static void thread_join(Thread t) { pthread_join(t, NULL); }

/* A one-shot start gate for n threads; a mutex and a condition variable rather than
 * pthread_barrier_t, which macOS lacks. */
typedef struct {
    pthread_mutex_t lock;
    pthread_cond_t all_in;
    unsigned n, arrived;
} Gate;
static int gate_init(Gate *g, unsigned n) {
    g->n = n;
    g->arrived = 0;
    if (pthread_mutex_init(&g->lock, NULL)) return -1;
    if (pthread_cond_init(&g->all_in, NULL)) {
        pthread_mutex_destroy(&g->lock);
        return -1;
    }
    return 0;
}
static void gate_wait(Gate *g) {
    pthread_mutex_lock(&g->lock);
    if (++g->arrived == g->n) pthread_cond_broadcast(&g->all_in);
    while (g->arrived < g->n) pthread_cond_wait(&g->all_in, &g->lock);
    pthread_mutex_unlock(&g->lock);
}
static void gate_destroy(Gate *g) {
    pthread_cond_destroy(&g->all_in);
    pthread_mutex_destroy(&g->lock);
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif

/* ----- FMI 2.0 types ---------------------------------------------------------------------- */

typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef void *fmi2FMUstate;
typedef unsigned int fmi2ValueReference;
typedef double fmi2Real;
typedef int fmi2Integer;
typedef int fmi2Boolean;
typedef char fmi2Char;
typedef const fmi2Char *fmi2String;
typedef char fmi2Byte;

#define fmi2True 1
#define fmi2False 0

typedef enum { fmi2OK, fmi2Warning, fmi2Discard, fmi2Error, fmi2Fatal, fmi2Pending } fmi2Status;
typedef enum { fmi2ModelExchange, fmi2CoSimulation } fmi2Type;
typedef enum {
    fmi2DoStepStatus,
    fmi2PendingStatus,
    fmi2LastSuccessfulTime,
    fmi2Terminated
} fmi2StatusKind;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String,
                                   fmi2String, ...);
typedef void *(*fmi2CallbackAllocateMemory)(size_t, size_t);
typedef void (*fmi2CallbackFreeMemory)(void *);
typedef void (*fmi2StepFinished)(fmi2ComponentEnvironment, fmi2Status);

/* fmi2FunctionTypes.h declares the members const; they are left unqualified here (same layout)
 * so that the struct can be filled by assignment, which is all a host needs. */
typedef struct {
    fmi2CallbackLogger logger;
    fmi2CallbackAllocateMemory allocateMemory;
    fmi2CallbackFreeMemory freeMemory;
    fmi2StepFinished stepFinished;
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

typedef const char *fmi2GetTypesPlatformTYPE(void);
typedef const char *fmi2GetVersionTYPE(void);
typedef fmi2Status fmi2SetDebugLoggingTYPE(fmi2Component, fmi2Boolean, size_t, const fmi2String[]);
typedef fmi2Component fmi2InstantiateTYPE(fmi2String, fmi2Type, fmi2String, fmi2String,
                                          const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);
typedef void fmi2FreeInstanceTYPE(fmi2Component);
typedef fmi2Status fmi2SetupExperimentTYPE(fmi2Component, fmi2Boolean, fmi2Real, fmi2Real,
                                           fmi2Boolean, fmi2Real);
typedef fmi2Status fmi2ComponentFunctionTYPE(fmi2Component); /* Enter/Exit init, Terminate, Reset */
typedef fmi2Status fmi2GetRealTYPE(fmi2Component, const fmi2ValueReference[], size_t, fmi2Real[]);
typedef fmi2Status fmi2SetRealTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                   const fmi2Real[]);
typedef fmi2Status fmi2GetIntegerTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                      fmi2Integer[]);
typedef fmi2Status fmi2SetIntegerTYPE(fmi2Component, const fmi2ValueReference[], size_t,
                                      const fmi2Integer[]);
typedef fmi2Status fmi2GetFMUstateTYPE(fmi2Component, fmi2FMUstate *);
typedef fmi2Status fmi2SetFMUstateTYPE(fmi2Component, fmi2FMUstate);
typedef fmi2Status fmi2FreeFMUstateTYPE(fmi2Component, fmi2FMUstate *);
typedef fmi2Status fmi2SerializedFMUstateSizeTYPE(fmi2Component, fmi2FMUstate, size_t *);
typedef fmi2Status fmi2SerializeFMUstateTYPE(fmi2Component, fmi2FMUstate, fmi2Byte[], size_t);
typedef fmi2Status fmi2DeSerializeFMUstateTYPE(fmi2Component, const fmi2Byte[], size_t,
                                               fmi2FMUstate *);
typedef fmi2Status fmi2DoStepTYPE(fmi2Component, fmi2Real, fmi2Real, fmi2Boolean);
typedef fmi2Status fmi2SetRealInputDerivativesTYPE(fmi2Component, const fmi2ValueReference[],
                                                   size_t, const fmi2Integer[], const fmi2Real[]);
typedef fmi2Status fmi2GetRealStatusTYPE(fmi2Component, const fmi2StatusKind, fmi2Real *);
typedef fmi2Status fmi2GetBooleanStatusTYPE(fmi2Component, const fmi2StatusKind, fmi2Boolean *);

/* Model Exchange (fmi2FunctionTypes.h). */
typedef struct {
    fmi2Boolean newDiscreteStatesNeeded;
    fmi2Boolean terminateSimulation;
    fmi2Boolean nominalsOfContinuousStatesChanged;
    fmi2Boolean valuesOfContinuousStatesChanged;
    fmi2Boolean nextEventTimeDefined;
    fmi2Real nextEventTime;
} fmi2EventInfo;
typedef fmi2Status fmi2NewDiscreteStatesTYPE(fmi2Component, fmi2EventInfo *);
typedef fmi2Status fmi2CompletedIntegratorStepTYPE(fmi2Component, fmi2Boolean, fmi2Boolean *,
                                                   fmi2Boolean *);
typedef fmi2Status fmi2SetTimeTYPE(fmi2Component, fmi2Real);
typedef fmi2Status fmi2SetContinuousStatesTYPE(fmi2Component, const fmi2Real[], size_t);
typedef fmi2Status fmi2GetRealArrayTYPE(fmi2Component, fmi2Real[], size_t); /* derivatives etc. */

/* Every function an FMU with both interfaces must export (fmi-notes: 25 common + 9 CS + 10 ME);
 * all are looked up so that a missing export fails here, as it would in FMPy. */
static const char *const ALL_EXPORTS[] = {
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate",
    "fmi2FreeInstance", "fmi2SetupExperiment", "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset", "fmi2GetReal", "fmi2GetInteger",
    "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean",
    "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative", "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives",
    "fmi2DoStep", "fmi2CancelStep", "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus", "fmi2GetStringStatus", "fmi2EnterEventMode", "fmi2NewDiscreteStates",
    "fmi2EnterContinuousTimeMode", "fmi2CompletedIntegratorStep", "fmi2SetTime",
    "fmi2SetContinuousStates", "fmi2GetDerivatives", "fmi2GetEventIndicators",
    "fmi2GetContinuousStates", "fmi2GetNominalsOfContinuousStates",
};
#define N_EXPORTS (sizeof ALL_EXPORTS / sizeof ALL_EXPORTS[0])

/* The functions this host calls. */
typedef struct {
    fmi2GetTypesPlatformTYPE *GetTypesPlatform;
    fmi2GetVersionTYPE *GetVersion;
    fmi2SetDebugLoggingTYPE *SetDebugLogging;
    fmi2InstantiateTYPE *Instantiate;
    fmi2FreeInstanceTYPE *FreeInstance;
    fmi2SetupExperimentTYPE *SetupExperiment;
    fmi2ComponentFunctionTYPE *EnterInitializationMode;
    fmi2ComponentFunctionTYPE *ExitInitializationMode;
    fmi2ComponentFunctionTYPE *Terminate;
    fmi2ComponentFunctionTYPE *Reset;
    fmi2GetRealTYPE *GetReal;
    fmi2SetRealTYPE *SetReal;
    fmi2GetIntegerTYPE *GetInteger;
    fmi2SetIntegerTYPE *SetInteger;
    fmi2GetFMUstateTYPE *GetFMUstate;
    fmi2SetFMUstateTYPE *SetFMUstate;
    fmi2FreeFMUstateTYPE *FreeFMUstate;
    fmi2SerializedFMUstateSizeTYPE *SerializedFMUstateSize;
    fmi2SerializeFMUstateTYPE *SerializeFMUstate;
    fmi2DeSerializeFMUstateTYPE *DeSerializeFMUstate;
    fmi2DoStepTYPE *DoStep;
    fmi2SetRealInputDerivativesTYPE *SetRealInputDerivatives;
    fmi2GetRealStatusTYPE *GetRealStatus;
    fmi2GetBooleanStatusTYPE *GetBooleanStatus;
    fmi2ComponentFunctionTYPE *EnterEventMode;
    fmi2NewDiscreteStatesTYPE *NewDiscreteStates;
    fmi2ComponentFunctionTYPE *EnterContinuousTimeMode;
    fmi2CompletedIntegratorStepTYPE *CompletedIntegratorStep;
    fmi2SetTimeTYPE *SetTime;
    fmi2SetContinuousStatesTYPE *SetContinuousStates;
    fmi2GetRealArrayTYPE *GetDerivatives;
    fmi2GetRealArrayTYPE *GetEventIndicators;
    fmi2GetRealArrayTYPE *GetContinuousStates;
    fmi2GetRealArrayTYPE *GetNominalsOfContinuousStates;
} Api;

/* ----- FMI 3.0 types ---------------------------------------------------------------------- */

/* From fmi3PlatformTypes.h and fmi3FunctionTypes.h (FMI 3.0): the types, the callbacks, and
 * the function types of the functions this host calls. */

typedef void *fmi3Instance;
typedef void *fmi3InstanceEnvironment;
typedef void *fmi3FMUState;
typedef uint32_t fmi3ValueReference;
typedef double fmi3Float64;
typedef int32_t fmi3Int32;
typedef int64_t fmi3Int64;
typedef bool fmi3Boolean;
typedef char fmi3Char;
typedef const fmi3Char *fmi3String;
typedef uint8_t fmi3Byte;

#define fmi3True true
#define fmi3False false

typedef enum { fmi3OK, fmi3Warning, fmi3Discard, fmi3Error, fmi3Fatal } fmi3Status;

/* The message as it is: not a format, no variadic arguments, no instance name. */
typedef void (*fmi3LogMessageCallback)(fmi3InstanceEnvironment, fmi3Status, fmi3String category,
                                       fmi3String message);
typedef void (*fmi3ClockUpdateCallback)(fmi3InstanceEnvironment);
typedef void (*fmi3IntermediateUpdateCallback)(
    fmi3InstanceEnvironment, fmi3Float64 intermediateUpdateTime,
    fmi3Boolean intermediateVariableSetRequested, fmi3Boolean intermediateVariableGetAllowed,
    fmi3Boolean intermediateStepFinished, fmi3Boolean canReturnEarly,
    fmi3Boolean *earlyReturnRequested, fmi3Float64 *earlyReturnTime);
typedef void (*fmi3LockPreemptionCallback)(void);
typedef void (*fmi3UnlockPreemptionCallback)(void);

typedef const char *fmi3GetVersionTYPE(void);
typedef fmi3Status fmi3SetDebugLoggingTYPE(fmi3Instance, fmi3Boolean, size_t, const fmi3String[]);
typedef fmi3Instance fmi3InstantiateModelExchangeTYPE(fmi3String instanceName,
                                                      fmi3String instantiationToken,
                                                      fmi3String resourcePath, fmi3Boolean visible,
                                                      fmi3Boolean loggingOn,
                                                      fmi3InstanceEnvironment,
                                                      fmi3LogMessageCallback);
typedef fmi3Instance fmi3InstantiateCoSimulationTYPE(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment, fmi3LogMessageCallback,
    fmi3IntermediateUpdateCallback);
typedef fmi3Instance fmi3InstantiateScheduledExecutionTYPE(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment, fmi3LogMessageCallback,
    fmi3ClockUpdateCallback, fmi3LockPreemptionCallback, fmi3UnlockPreemptionCallback);
typedef void fmi3FreeInstanceTYPE(fmi3Instance);
typedef fmi3Status fmi3EnterInitializationModeTYPE(fmi3Instance, fmi3Boolean toleranceDefined,
                                                   fmi3Float64 tolerance, fmi3Float64 startTime,
                                                   fmi3Boolean stopTimeDefined,
                                                   fmi3Float64 stopTime);
/* ExitInitializationMode, EnterEventMode, Terminate, Reset, EnterConfigurationMode,
 * EnterContinuousTimeMode: the header declares each with this shape. */
typedef fmi3Status fmi3InstanceFunctionTYPE(fmi3Instance);
typedef fmi3Status fmi3GetFloat64TYPE(fmi3Instance, const fmi3ValueReference[], size_t,
                                      fmi3Float64[], size_t nValues);
typedef fmi3Status fmi3SetFloat64TYPE(fmi3Instance, const fmi3ValueReference[], size_t,
                                      const fmi3Float64[], size_t nValues);
typedef fmi3Status fmi3SetInt64TYPE(fmi3Instance, const fmi3ValueReference[], size_t,
                                    const fmi3Int64[], size_t nValues);
typedef fmi3Status fmi3SetUInt64TYPE(fmi3Instance, const fmi3ValueReference[], size_t,
                                     const uint64_t[], size_t nValues);
typedef fmi3Status fmi3GetFMUStateTYPE(fmi3Instance, fmi3FMUState *);
typedef fmi3Status fmi3SetFMUStateTYPE(fmi3Instance, fmi3FMUState);
typedef fmi3Status fmi3FreeFMUStateTYPE(fmi3Instance, fmi3FMUState *);
typedef fmi3Status fmi3SerializedFMUStateSizeTYPE(fmi3Instance, fmi3FMUState, size_t *);
typedef fmi3Status fmi3SerializeFMUStateTYPE(fmi3Instance, fmi3FMUState, fmi3Byte[], size_t);
typedef fmi3Status fmi3DeserializeFMUStateTYPE(fmi3Instance, const fmi3Byte[], size_t,
                                               fmi3FMUState *);
typedef fmi3Status fmi3UpdateDiscreteStatesTYPE(fmi3Instance,
                                                fmi3Boolean *discreteStatesNeedUpdate,
                                                fmi3Boolean *terminateSimulation,
                                                fmi3Boolean *nominalsOfContinuousStatesChanged,
                                                fmi3Boolean *valuesOfContinuousStatesChanged,
                                                fmi3Boolean *nextEventTimeDefined,
                                                fmi3Float64 *nextEventTime);
typedef fmi3Status fmi3CompletedIntegratorStepTYPE(fmi3Instance,
                                                   fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                                   fmi3Boolean *enterEventMode,
                                                   fmi3Boolean *terminateSimulation);
typedef fmi3Status fmi3SetTimeTYPE(fmi3Instance, fmi3Float64);
typedef fmi3Status fmi3SetContinuousStatesTYPE(fmi3Instance, const fmi3Float64[], size_t);
/* GetContinuousStateDerivatives, GetEventIndicators, GetContinuousStates,
 * GetNominalsOfContinuousStates */
typedef fmi3Status fmi3GetFloat64ArrayTYPE(fmi3Instance, fmi3Float64[], size_t);
typedef fmi3Status fmi3GetNumberOfTYPE(fmi3Instance, size_t *); /* states, event indicators */
typedef fmi3Status fmi3DoStepTYPE(fmi3Instance, fmi3Float64 currentCommunicationPoint,
                                  fmi3Float64 communicationStepSize,
                                  fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                  fmi3Boolean *eventHandlingNeeded,
                                  fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                                  fmi3Float64 *lastSuccessfulTime);

/* The 75 functions of fmi3Functions.h: common, Model Exchange, co-simulation, scheduled
 * execution. An FMU exports all of them whatever it provides. */
static const char *const ALL_EXPORTS3[] = {
    "fmi3GetVersion", "fmi3SetDebugLogging", "fmi3InstantiateModelExchange",
    "fmi3InstantiateCoSimulation", "fmi3InstantiateScheduledExecution", "fmi3FreeInstance",
    "fmi3EnterInitializationMode", "fmi3ExitInitializationMode", "fmi3EnterEventMode",
    "fmi3Terminate", "fmi3Reset", "fmi3GetFloat32", "fmi3GetFloat64", "fmi3GetInt8",
    "fmi3GetUInt8", "fmi3GetInt16", "fmi3GetUInt16", "fmi3GetInt32", "fmi3GetUInt32",
    "fmi3GetInt64", "fmi3GetUInt64", "fmi3GetBoolean", "fmi3GetString", "fmi3GetBinary",
    "fmi3GetClock", "fmi3SetFloat32", "fmi3SetFloat64", "fmi3SetInt8", "fmi3SetUInt8",
    "fmi3SetInt16", "fmi3SetUInt16", "fmi3SetInt32", "fmi3SetUInt32", "fmi3SetInt64",
    "fmi3SetUInt64", "fmi3SetBoolean", "fmi3SetString", "fmi3SetBinary", "fmi3SetClock",
    "fmi3GetNumberOfVariableDependencies", "fmi3GetVariableDependencies", "fmi3GetFMUState",
    "fmi3SetFMUState", "fmi3FreeFMUState", "fmi3SerializedFMUStateSize",
    "fmi3SerializeFMUState", "fmi3DeserializeFMUState", "fmi3GetDirectionalDerivative",
    "fmi3GetAdjointDerivative", "fmi3EnterConfigurationMode", "fmi3ExitConfigurationMode",
    "fmi3GetIntervalDecimal", "fmi3GetIntervalFraction", "fmi3GetShiftDecimal",
    "fmi3GetShiftFraction", "fmi3SetIntervalDecimal", "fmi3SetIntervalFraction",
    "fmi3SetShiftDecimal", "fmi3SetShiftFraction", "fmi3EvaluateDiscreteStates",
    "fmi3UpdateDiscreteStates", "fmi3EnterContinuousTimeMode", "fmi3CompletedIntegratorStep",
    "fmi3SetTime", "fmi3SetContinuousStates", "fmi3GetContinuousStateDerivatives",
    "fmi3GetEventIndicators", "fmi3GetContinuousStates", "fmi3GetNominalsOfContinuousStates",
    "fmi3GetNumberOfEventIndicators", "fmi3GetNumberOfContinuousStates", "fmi3EnterStepMode",
    "fmi3GetOutputDerivatives", "fmi3DoStep", "fmi3ActivateModelPartition",
};
#define N_EXPORTS3 (sizeof ALL_EXPORTS3 / sizeof ALL_EXPORTS3[0])

/* The FMI 3.0 functions this host calls. */
typedef struct {
    fmi3GetVersionTYPE *GetVersion;
    fmi3SetDebugLoggingTYPE *SetDebugLogging;
    fmi3InstantiateModelExchangeTYPE *InstantiateModelExchange;
    fmi3InstantiateCoSimulationTYPE *InstantiateCoSimulation;
    fmi3InstantiateScheduledExecutionTYPE *InstantiateScheduledExecution;
    fmi3FreeInstanceTYPE *FreeInstance;
    fmi3EnterInitializationModeTYPE *EnterInitializationMode;
    fmi3InstanceFunctionTYPE *ExitInitializationMode;
    fmi3InstanceFunctionTYPE *EnterEventMode;
    fmi3InstanceFunctionTYPE *Terminate;
    fmi3InstanceFunctionTYPE *Reset;
    fmi3InstanceFunctionTYPE *EnterConfigurationMode;
    fmi3InstanceFunctionTYPE *ExitConfigurationMode;
    fmi3SetUInt64TYPE *SetUInt64;
    fmi3GetFloat64TYPE *GetFloat64;
    fmi3SetFloat64TYPE *SetFloat64;
    fmi3SetInt64TYPE *SetInt64;
    fmi3GetFMUStateTYPE *GetFMUState;
    fmi3SetFMUStateTYPE *SetFMUState;
    fmi3FreeFMUStateTYPE *FreeFMUState;
    fmi3SerializedFMUStateSizeTYPE *SerializedFMUStateSize;
    fmi3SerializeFMUStateTYPE *SerializeFMUState;
    fmi3DeserializeFMUStateTYPE *DeserializeFMUState;
    fmi3UpdateDiscreteStatesTYPE *UpdateDiscreteStates;
    fmi3InstanceFunctionTYPE *EnterContinuousTimeMode;
    fmi3CompletedIntegratorStepTYPE *CompletedIntegratorStep;
    fmi3SetTimeTYPE *SetTime;
    fmi3SetContinuousStatesTYPE *SetContinuousStates;
    fmi3GetFloat64ArrayTYPE *GetContinuousStateDerivatives;
    fmi3GetFloat64ArrayTYPE *GetEventIndicators;
    fmi3GetFloat64ArrayTYPE *GetContinuousStates;
    fmi3GetFloat64ArrayTYPE *GetNominalsOfContinuousStates;
    fmi3GetNumberOfTYPE *GetNumberOfContinuousStates;
    fmi3GetNumberOfTYPE *GetNumberOfEventIndicators;
    fmi3DoStepTYPE *DoStep;
} Api3;

/* ----- the model's interface, read from modelDescription.xml ------------------------------- */

typedef struct {
    int fmi3;       /* read from an FMI 3.0 modelDescription */
    char guid[128]; /* FMI 3.0: the instantiationToken */
    fmi2ValueReference ei, phi_end, phi_source, v1, theta1, u2;
    fmi2ValueReference phi, fixed_step, phi_interpolation; /* for --bench-dostep */
    fmi2ValueReference beam, integrator, n_elements2;      /* --bench-dostep, FMI 2.0 */
    fmi2ValueReference time, intermediate_step;            /* FMI 3.0 only */
    fmi2ValueReference n_elements, nodal_v;                /* FMI 3.0 only: arrays */
} Model;

#define PHI_SOURCE_INPUT 1
#define PHI_SOURCE_LAW 2 /* enumeration PhiSource: 1 = input (the start value), 2 = law */

/* The paper's scene: communication points k*H for k = 0..N_STEPS (k*H, not a running sum, as
 * FMPy's simulate_fmu and the CLI's output grid compute them). */
#define H 0.01
#define N_STEPS 1020
#define T_END 10.2
#define PI 3.14159265358979323846

/* ----- failures ----------------------------------------------------------------------------- */

/* A check that fails writes its message into the caller's buffer and returns -1; each thread
 * has its own buffer, and main prints them. */
typedef struct {
    char msg[512];
} Err;

static int fail(Err *e, const char *fmt, ...) PRINTF_LIKE(2, 3);
static int fail(Err *e, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->msg, sizeof e->msg, fmt, ap);
    va_end(ap);
    return -1;
}

/* The FMI version the checks run through (--fmi3: 3), for the names of statuses. */
static int g_fmi = 2;

/* Not a status of the FMU: an adapter of FMI 3.0 (see "FMI 3.0 behind FMI 2.0's signatures")
 * found a wrong out-argument in a call that returned fmi3OK; its message is the instance's last. */
#define HOST_CHECK_FAILED 7

static const char *status_name(int s) {
    static const char *const names[2][6] = {
        {"fmi2OK", "fmi2Warning", "fmi2Discard", "fmi2Error", "fmi2Fatal", "fmi2Pending"},
        {"fmi3OK", "fmi3Warning", "fmi3Discard", "fmi3Error", "fmi3Fatal", "(not an fmi3Status)"}};
    if (s == HOST_CHECK_FAILED) return "fmi3OK with an out-argument the host refuses";
    return s >= 0 && s <= 5 ? names[g_fmi == 3][s] : "(not a status)";
}

/* Calls `call`, which must return fmi2OK (fmi3OK); otherwise records the call's text, line,
 * status and the instance's last log message, and jumps to the function's `out` label. Expects
 * `who` (a name for the message), `lc` (the instance's LogCtx) and `err` in scope. The status is
 * taken as an int: fmi2Status and fmi3Status are different enums with the same values. */
#define OK(call)                                                                               \
    do {                                                                                       \
        int got_ = (int)(call);                                                                \
        if (got_ != fmi2OK) {                                                                  \
            fail(err, "%s: line %d: %s returned %s (last message: `%s`)", who, __LINE__, #call, \
                 status_name(got_), lc->last);                                                 \
            goto out;                                                                          \
        }                                                                                      \
    } while (0)

/* A call out of sequence or with a bad argument: it must return fmi2Error (fmi3Error) and log
 * exactly one error (which the logger then does not count as unexpected). */
#define REFUSED(call)                                                                          \
    do {                                                                                       \
        long before_ = lc->count[fmi2Error];                                                   \
        lc->expect_errors = 1;                                                                 \
        int got_ = (int)(call);                                                                \
        lc->expect_errors = 0;                                                                 \
        if (got_ != fmi2Error || lc->count[fmi2Error] != before_ + 1) {                        \
            fail(err, "%s: line %d: %s returned %s with %ld error messages, expected "         \
                      "%s and one message",                                                    \
                 who, __LINE__, #call, status_name(got_), lc->count[fmi2Error] - before_,      \
                 status_name(fmi2Error));                                                      \
            goto out;                                                                          \
        }                                                                                      \
    } while (0)

/* ----- the logger --------------------------------------------------------------------------- */

/* The componentEnvironment of every instance: the logger checks that the FMU hands it back
 * unchanged, with the instance's own name, and counts the messages by status. An instance is
 * used by one thread at a time, so its context needs no lock. */
#define CTX_MAGIC 0x4642484fu
typedef struct {
    unsigned magic;
    char name[64];
    int expect_errors; /* 1 while a call is expected to log an error */
    int quiet;         /* 1: do not print expected messages */
    long count[6];     /* messages by fmi2Status */
    char last[256];    /* the last message, formatted */
} LogCtx;

/* Messages that arrive with a wrong environment or instance name, or with a category the
 * modelDescription does not declare; counted across threads. */
static atomic_long g_bad_log = 0;
static atomic_long g_messages = 0;

static const char *const CATEGORIES[] = {"logStatusWarning", "logStatusDiscard", "logStatusError",
                                         "logStatusFatal",   "logCalls",         "logAll"};

/* What both loggers do with a message (`instanceName`: NULL from FMI 3.0, whose callback has
 * none; `status` the same number in fmi2Status and fmi3Status). */
static void log_message(void *env, int fmi3, fmi2String instanceName, int status,
                        fmi2String category, const char *text) {
    atomic_fetch_add(&g_messages, 1);

    LogCtx *ctx = env;
    if (ctx == NULL || ctx->magic != CTX_MAGIC) {
        atomic_fetch_add(&g_bad_log, 1);
        fprintf(stderr, "logger: componentEnvironment %p is not the host's: %s\n", env, text);
        return;
    }
    int known = 0;
    for (size_t k = 0; category && k < sizeof CATEGORIES / sizeof CATEGORIES[0]; k++)
        known |= strcmp(category, CATEGORIES[k]) == 0;
    if ((!fmi3 && (!instanceName || strcmp(instanceName, ctx->name) != 0)) || !known) {
        atomic_fetch_add(&g_bad_log, 1);
        fprintf(stderr, "logger: [%s] instanceName `%s` (expected `%s`), category `%s`: %s\n",
                status_name(status), instanceName ? instanceName : "(null)", ctx->name,
                category ? category : "(null)", text);
    }
    if (status >= 0 && status <= 5) ctx->count[status]++;
    size_t len = strnlen(text, sizeof ctx->last - 1); /* truncation is fine for a reminder */
    memcpy(ctx->last, text, len);
    ctx->last[len] = '\0';
    if (status >= fmi2Discard && !ctx->expect_errors) {
        atomic_fetch_add(&g_bad_log, 1);
        fprintf(stderr, "logger: unexpected %s from `%s` [%s]: %s\n", status_name(status),
                ctx->name, category ? category : "(null)", text);
    } else if (!ctx->quiet && status >= fmi2Warning) {
        fprintf(stderr, "logger: (expected) %s from `%s`: %s\n", status_name(status), ctx->name,
                text);
    }
}

static void logger(fmi2ComponentEnvironment env, fmi2String instanceName, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    char text[1024];
    va_list ap;
    va_start(ap, message);
    /* printf-like, as the standard requires: the FMU passes "%s" and the text. */
    vsnprintf(text, sizeof text, message ? message : "(null format)", ap);
    va_end(ap);
    log_message(env, 0, instanceName, (int)status, category, text);
}

/* FMI 3.0's logMessage: the message is the text itself (a '%' in it is just a character). */
static void logger3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                    fmi3String message) {
    log_message(env, 1, NULL, (int)status, category, message ? message : "(null message)");
}

static void ctx_init(LogCtx *ctx, const char *name) {
    memset(ctx, 0, sizeof *ctx);
    ctx->magic = CTX_MAGIC;
    ctx->quiet = 1;
    snprintf(ctx->name, sizeof ctx->name, "%s", name);
}

/* ----- loading ------------------------------------------------------------------------------ */

/* The whole file, NUL-terminated (for the XML); its length into *size if size is not NULL. */
static char *read_file(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 1 << 16, n = 0;
    char *buf = malloc(cap);
    size_t got;
    while (buf && (got = fread(buf + n, 1, cap - n - 1, f)) > 0) {
        n += got;
        if (n + 1 == cap) {
            char *bigger = realloc(buf, cap *= 2);
            if (!bigger) free(buf);
            buf = bigger;
        }
    }
    int bad = ferror(f);
    fclose(f);
    if (buf && bad) {
        free(buf);
        buf = NULL;
    }
    if (buf) buf[n] = '\0';
    if (size) *size = n;
    return buf;
}

/* The value reference of the variable called `name` (xtask writes `name` then
 * `valueReference`, in that order, on one line): a ScalarVariable in FMI 2.0, in FMI 3.0 an
 * element named by its type, `type` (Float64, Enumeration, ...). */
static int find_vr(const char *xml, const Model *m, const char *type, const char *name,
                   fmi2ValueReference *vr, Err *err) {
    char key[96];
    const char *element = m->fmi3 ? type : "ScalarVariable";
    snprintf(key, sizeof key, "<%s name=\"%s\" valueReference=\"", element, name);
    const char *p = strstr(xml, key);
    if (!p) return fail(err, "modelDescription.xml: no %s named `%s`", element, name);
    *vr = (fmi2ValueReference)strtoul(p + strlen(key), NULL, 10);
    return 0;
}

/* The modelDescription.xml of an FMI 2.0 FMU, or with `fmi3` of an FMI 3.0 one. */
static int read_model(const char *unzipdir, int fmi3, Model *m, Err *err) {
    char path[4096];
    snprintf(path, sizeof path, "%s/modelDescription.xml", unzipdir);
    char *xml = read_file(path, NULL);
    if (!xml) return fail(err, "cannot read %s", path);
    int rc = -1;
    m->fmi3 = fmi3;
    const char *version = fmi3 ? "fmiVersion=\"3.0\"" : "fmiVersion=\"2.0\"";
    if (!strstr(xml, version)) {
        fail(err, "%s: not an FMI %s model description (no %s)", path, fmi3 ? "3.0" : "2.0",
             version);
        goto out;
    }
    const char *attr = fmi3 ? " instantiationToken=\"" : " guid=\"";
    const char *g = strstr(xml, attr);
    if (g) g += strlen(attr);
    const char *end = g ? strchr(g, '"') : NULL;
    if (!g || !end || (size_t)(end - g) >= sizeof m->guid) {
        fail(err, "%s: no%s attribute", path, attr);
        goto out;
    }
    memcpy(m->guid, g, (size_t)(end - g));
    m->guid[end - g] = '\0';
    if (find_vr(xml, m, "Float64", "EI", &m->ei, err) ||
        find_vr(xml, m, "Float64", "phi_end", &m->phi_end, err) ||
        find_vr(xml, m, "Enumeration", "phi_source", &m->phi_source, err) ||
        find_vr(xml, m, "Float64", "v1", &m->v1, err) ||
        find_vr(xml, m, "Float64", "theta1", &m->theta1, err) ||
        find_vr(xml, m, "Float64", "u2", &m->u2, err) ||
        find_vr(xml, m, "Float64", "phi", &m->phi, err) ||
        find_vr(xml, m, "Float64", "fixed_step", &m->fixed_step, err) ||
        find_vr(xml, m, "Enumeration", "phi_interpolation", &m->phi_interpolation, err) ||
        find_vr(xml, m, "Enumeration", "beam", &m->beam, err) ||
        find_vr(xml, m, "Enumeration", "integrator", &m->integrator, err))
        goto out;
    if (!fmi3 && find_vr(xml, m, "Int32", "n_elements", &m->n_elements2, err)) goto out;
    if (fmi3 && (find_vr(xml, m, "Float64", "time", &m->time, err) ||
                 find_vr(xml, m, "Float64", "intermediate_step", &m->intermediate_step, err) ||
                 find_vr(xml, m, "UInt64", "n_elements", &m->n_elements, err) ||
                 find_vr(xml, m, "Float64", "nodal_v", &m->nodal_v, err)))
        goto out;
    rc = 0;
out:
    free(xml);
    return rc;
}

static int load_api(Lib lib, Api *api, Err *err) {
    for (size_t k = 0; k < N_EXPORTS; k++)
        if (!lib_sym(lib, ALL_EXPORTS[k]))
            return fail(err, "the library does not export %s (%s)", ALL_EXPORTS[k], lib_error());
#define SYM(field, name) api->field = (__typeof__(api->field))lib_sym(lib, name)
    SYM(GetTypesPlatform, "fmi2GetTypesPlatform");
    SYM(GetVersion, "fmi2GetVersion");
    SYM(SetDebugLogging, "fmi2SetDebugLogging");
    SYM(Instantiate, "fmi2Instantiate");
    SYM(FreeInstance, "fmi2FreeInstance");
    SYM(SetupExperiment, "fmi2SetupExperiment");
    SYM(EnterInitializationMode, "fmi2EnterInitializationMode");
    SYM(ExitInitializationMode, "fmi2ExitInitializationMode");
    SYM(Terminate, "fmi2Terminate");
    SYM(Reset, "fmi2Reset");
    SYM(GetReal, "fmi2GetReal");
    SYM(SetReal, "fmi2SetReal");
    SYM(GetInteger, "fmi2GetInteger");
    SYM(SetInteger, "fmi2SetInteger");
    SYM(GetFMUstate, "fmi2GetFMUstate");
    SYM(SetFMUstate, "fmi2SetFMUstate");
    SYM(FreeFMUstate, "fmi2FreeFMUstate");
    SYM(SerializedFMUstateSize, "fmi2SerializedFMUstateSize");
    SYM(SerializeFMUstate, "fmi2SerializeFMUstate");
    SYM(DeSerializeFMUstate, "fmi2DeSerializeFMUstate");
    SYM(DoStep, "fmi2DoStep");
    SYM(SetRealInputDerivatives, "fmi2SetRealInputDerivatives");
    SYM(GetRealStatus, "fmi2GetRealStatus");
    SYM(GetBooleanStatus, "fmi2GetBooleanStatus");
    SYM(EnterEventMode, "fmi2EnterEventMode");
    SYM(NewDiscreteStates, "fmi2NewDiscreteStates");
    SYM(EnterContinuousTimeMode, "fmi2EnterContinuousTimeMode");
    SYM(CompletedIntegratorStep, "fmi2CompletedIntegratorStep");
    SYM(SetTime, "fmi2SetTime");
    SYM(SetContinuousStates, "fmi2SetContinuousStates");
    SYM(GetDerivatives, "fmi2GetDerivatives");
    SYM(GetEventIndicators, "fmi2GetEventIndicators");
    SYM(GetContinuousStates, "fmi2GetContinuousStates");
    SYM(GetNominalsOfContinuousStates, "fmi2GetNominalsOfContinuousStates");
#undef SYM
    if (strcmp(api->GetVersion(), "2.0") != 0)
        return fail(err, "fmi2GetVersion() = `%s`, expected `2.0`", api->GetVersion());
    if (strcmp(api->GetTypesPlatform(), "default") != 0)
        return fail(err, "fmi2GetTypesPlatform() = `%s`, expected `default`",
                    api->GetTypesPlatform());
    return 0;
}

static int load_api3(Lib lib, Api3 *api, Err *err) {
    for (size_t k = 0; k < N_EXPORTS3; k++)
        if (!lib_sym(lib, ALL_EXPORTS3[k]))
            return fail(err, "the library does not export %s (%s)", ALL_EXPORTS3[k], lib_error());
#define SYM(field) api->field = (__typeof__(api->field))lib_sym(lib, "fmi3" #field)
    SYM(GetVersion);
    SYM(SetDebugLogging);
    SYM(InstantiateModelExchange);
    SYM(InstantiateCoSimulation);
    SYM(InstantiateScheduledExecution);
    SYM(FreeInstance);
    SYM(EnterInitializationMode);
    SYM(ExitInitializationMode);
    SYM(EnterEventMode);
    SYM(Terminate);
    SYM(Reset);
    SYM(EnterConfigurationMode);
    SYM(ExitConfigurationMode);
    SYM(SetUInt64);
    SYM(GetFloat64);
    SYM(SetFloat64);
    SYM(SetInt64);
    SYM(GetFMUState);
    SYM(SetFMUState);
    SYM(FreeFMUState);
    SYM(SerializedFMUStateSize);
    SYM(SerializeFMUState);
    SYM(DeserializeFMUState);
    SYM(UpdateDiscreteStates);
    SYM(EnterContinuousTimeMode);
    SYM(CompletedIntegratorStep);
    SYM(SetTime);
    SYM(SetContinuousStates);
    SYM(GetContinuousStateDerivatives);
    SYM(GetEventIndicators);
    SYM(GetContinuousStates);
    SYM(GetNominalsOfContinuousStates);
    SYM(GetNumberOfContinuousStates);
    SYM(GetNumberOfEventIndicators);
    SYM(DoStep);
#undef SYM
    if (strcmp(api->GetVersion(), "3.0") != 0)
        return fail(err, "fmi3GetVersion() = `%s`, expected `3.0`", api->GetVersion());
    return 0;
}

/* ----- FMI 3.0 behind FMI 2.0's signatures ------------------------------------------------ */

/* Checks 1-4 call the FMI 2.0 functions of an Api. With --fmi3 they get an Api of the adapters
 * below instead, each an FMI 2.0 function made of FMI 3.0 calls, so that the same code runs the
 * same scenes through FMI 3.0. The component they hand around is then an Inst3: the FMI 3.0
 * instance, and what FMI 2.0 gives in a call that FMI 3.0 gives in another. What FMI 3.0 returns
 * in out-arguments and FMI 2.0 does not is checked here; a wrong one turns fmi3OK into
 * HOST_CHECK_FAILED, with the reason as the instance's last message. */

typedef struct {
    fmi3Instance inst;
    LogCtx *ctx; /* the instance environment */
    /* fmi2SetupExperiment's arguments, for fmi3EnterInitializationMode */
    bool tolerance_defined, stop_time_defined;
    double tolerance, start_time, stop_time;
} Inst3;

/* The FMI 3.0 functions the adapters call, and the value reference of `time`. */
static struct {
    Api3 f;
    fmi3ValueReference time;
} g3;

#define INST3(c) (((Inst3 *)(c))->inst)

static fmi2Status refuse_out(Inst3 *w, const char *fmt, ...) PRINTF_LIKE(2, 3);
static fmi2Status refuse_out(Inst3 *w, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(w->ctx->last, sizeof w->ctx->last, fmt, ap);
    va_end(ap);
    return (fmi2Status)HOST_CHECK_FAILED;
}

/* fmi2Instantiate: co-simulation without event mode, early return or intermediate variables;
 * Model Exchange; a type that is neither, FMI 3.0's third interface, which this FMU does not
 * provide (it must return NULL and log one error, as fmi2Instantiate does for such a type). */
static fmi2Component a3_instantiate(fmi2String name, fmi2Type type, fmi2String token,
                                    fmi2String resources, const fmi2CallbackFunctions *cb,
                                    fmi2Boolean visible, fmi2Boolean logging_on) {
    Inst3 *w = calloc(1, sizeof *w);
    if (!w) return NULL;
    void *env = cb->componentEnvironment;
    w->ctx = env;
    bool vis = visible != fmi2False, on = logging_on != fmi2False;
    if (type == fmi2CoSimulation)
        w->inst = g3.f.InstantiateCoSimulation(name, token, resources, vis, on, fmi3False,
                                               fmi3False, NULL, 0, env, logger3, NULL);
    else if (type == fmi2ModelExchange)
        w->inst = g3.f.InstantiateModelExchange(name, token, resources, vis, on, env, logger3);
    else
        w->inst = g3.f.InstantiateScheduledExecution(name, token, resources, vis, on, env, logger3,
                                                     NULL, NULL, NULL);
    if (!w->inst) {
        free(w);
        return NULL;
    }
    return w;
}

static void a3_free_instance(fmi2Component c) {
    if (!c) return;
    g3.f.FreeInstance(INST3(c));
    free(c);
}

static fmi2Status a3_set_debug_logging(fmi2Component c, fmi2Boolean on, size_t n,
                                       const fmi2String categories[]) {
    return (fmi2Status)g3.f.SetDebugLogging(INST3(c), on != fmi2False, n, categories);
}

/* FMI 3.0 takes the experiment's set-up with fmi3EnterInitializationMode: kept until then. */
static fmi2Status a3_setup_experiment(fmi2Component c, fmi2Boolean tolerance_defined,
                                      fmi2Real tolerance, fmi2Real start, fmi2Boolean stop_defined,
                                      fmi2Real stop) {
    Inst3 *w = c;
    w->tolerance_defined = tolerance_defined != fmi2False;
    w->tolerance = tolerance;
    w->start_time = start;
    w->stop_time_defined = stop_defined != fmi2False;
    w->stop_time = stop;
    return fmi2OK;
}

static fmi2Status a3_enter_initialization_mode(fmi2Component c) {
    Inst3 *w = c;
    return (fmi2Status)g3.f.EnterInitializationMode(w->inst, w->tolerance_defined, w->tolerance,
                                                    w->start_time, w->stop_time_defined,
                                                    w->stop_time);
}

#define A3_INSTANCE_FUNCTION(name, fn)                                                          \
    static fmi2Status name(fmi2Component c) { return (fmi2Status)g3.f.fn(INST3(c)); }
A3_INSTANCE_FUNCTION(a3_exit_initialization_mode, ExitInitializationMode)
A3_INSTANCE_FUNCTION(a3_terminate, Terminate)
A3_INSTANCE_FUNCTION(a3_reset, Reset)
A3_INSTANCE_FUNCTION(a3_enter_event_mode, EnterEventMode)
A3_INSTANCE_FUNCTION(a3_enter_continuous_time_mode, EnterContinuousTimeMode)

static fmi2Status a3_get_real(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                              fmi2Real value[]) {
    return (fmi2Status)g3.f.GetFloat64(INST3(c), vr, n, value, n);
}

static fmi2Status a3_set_real(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                              const fmi2Real value[]) {
    return (fmi2Status)g3.f.SetFloat64(INST3(c), vr, n, value, n);
}

/* The checks set enumerations only through fmi2SetInteger: FMI 3.0's are Int64. */
static fmi2Status a3_set_integer(fmi2Component c, const fmi2ValueReference vr[], size_t n,
                                 const fmi2Integer value[]) {
    fmi3Int64 wide[8];
    if (n > sizeof wide / sizeof wide[0])
        return refuse_out(c, "fmi2SetInteger adapter: %zu values, at most 8", n);
    for (size_t k = 0; k < n; k++) wide[k] = value[k];
    return (fmi2Status)g3.f.SetInt64(INST3(c), vr, n, wide, n);
}

static fmi2Status a3_get_fmu_state(fmi2Component c, fmi2FMUstate *s) {
    return (fmi2Status)g3.f.GetFMUState(INST3(c), s);
}
static fmi2Status a3_set_fmu_state(fmi2Component c, fmi2FMUstate s) {
    return (fmi2Status)g3.f.SetFMUState(INST3(c), s);
}
static fmi2Status a3_free_fmu_state(fmi2Component c, fmi2FMUstate *s) {
    return (fmi2Status)g3.f.FreeFMUState(INST3(c), s);
}
static fmi2Status a3_serialized_fmu_state_size(fmi2Component c, fmi2FMUstate s, size_t *size) {
    return (fmi2Status)g3.f.SerializedFMUStateSize(INST3(c), s, size);
}
static fmi2Status a3_serialize_fmu_state(fmi2Component c, fmi2FMUstate s, fmi2Byte bytes[],
                                         size_t size) {
    return (fmi2Status)g3.f.SerializeFMUState(INST3(c), s, (fmi3Byte *)bytes, size);
}
static fmi2Status a3_deserialize_fmu_state(fmi2Component c, const fmi2Byte bytes[], size_t size,
                                           fmi2FMUstate *s) {
    return (fmi2Status)g3.f.DeserializeFMUState(INST3(c), (const fmi3Byte *)bytes, size, s);
}

/* fmi3DoStep, its out-arguments checked when it returns fmi3OK (each set to the wrong value
 * before the call, so that one left unwritten shows). */
static fmi2Status a3_do_step(fmi2Component c, fmi2Real tc, fmi2Real h, fmi2Boolean no_prior) {
    Inst3 *w = c;
    bool event = true, terminate = true, early = true;
    double last = NAN;
    fmi3Status s = g3.f.DoStep(w->inst, tc, h, no_prior != fmi2False, &event, &terminate, &early,
                               &last);
    if (s == fmi3OK && (event || terminate || early || !(last == tc + h)))
        return refuse_out(w, "fmi3DoStep(tc = %.17g, h = %.17g): eventHandlingNeeded = %d, "
                             "terminateSimulation = %d, earlyReturn = %d, lastSuccessfulTime = "
                             "%.17g; expected false, false, false, tc + h = %.17g",
                          tc, h, event, terminate, early, last, tc + h);
    return (fmi2Status)s;
}

/* fmi2LastSuccessfulTime: FMI 3.0's fmi3DoStep returns it; at any other time (after a state
 * is restored) it is the independent variable `time`. */
static fmi2Status a3_get_real_status(fmi2Component c, const fmi2StatusKind kind, fmi2Real *value) {
    if (kind != fmi2LastSuccessfulTime)
        return refuse_out(c, "fmi2GetRealStatus adapter: kind %d is not fmi2LastSuccessfulTime",
                          (int)kind);
    return (fmi2Status)g3.f.GetFloat64(INST3(c), &g3.time, 1, value, 1);
}

/* fmi3UpdateDiscreteStates's six out-arguments into fmi2EventInfo. This model's only event is
 * the law's end, a time event: it changes neither the states' values nor their nominals. */
static fmi2Status a3_new_discrete_states(fmi2Component c, fmi2EventInfo *info) {
    bool need = true, terminate = true, nominals = true, values = true, defined = true;
    double next = NAN;
    fmi3Status s = g3.f.UpdateDiscreteStates(INST3(c), &need, &terminate, &nominals, &values,
                                             &defined, &next);
    *info = (fmi2EventInfo){need, terminate, nominals, values, defined, next};
    if (s == fmi3OK && (nominals || values || (defined && !isfinite(next))))
        return refuse_out(c, "fmi3UpdateDiscreteStates: nominalsOfContinuousStatesChanged = %d, "
                             "valuesOfContinuousStatesChanged = %d, nextEventTimeDefined = %d, "
                             "nextEventTime = %g",
                          nominals, values, defined, next);
    return (fmi2Status)s;
}

static fmi2Status a3_completed_integrator_step(fmi2Component c, fmi2Boolean no_prior,
                                               fmi2Boolean *enter, fmi2Boolean *terminate) {
    bool e = true, t = true;
    fmi3Status s = g3.f.CompletedIntegratorStep(INST3(c), no_prior != fmi2False, &e, &t);
    *enter = e, *terminate = t;
    return (fmi2Status)s;
}

static fmi2Status a3_set_time(fmi2Component c, fmi2Real t) {
    return (fmi2Status)g3.f.SetTime(INST3(c), t);
}
static fmi2Status a3_set_continuous_states(fmi2Component c, const fmi2Real x[], size_t n) {
    return (fmi2Status)g3.f.SetContinuousStates(INST3(c), x, n);
}

#define A3_ARRAY_FUNCTION(name, fn)                                                             \
    static fmi2Status name(fmi2Component c, fmi2Real x[], size_t n) {                           \
        return (fmi2Status)g3.f.fn(INST3(c), x, n);                                             \
    }
A3_ARRAY_FUNCTION(a3_get_derivatives, GetContinuousStateDerivatives)
A3_ARRAY_FUNCTION(a3_get_event_indicators, GetEventIndicators)
A3_ARRAY_FUNCTION(a3_get_continuous_states, GetContinuousStates)
A3_ARRAY_FUNCTION(a3_get_nominals, GetNominalsOfContinuousStates)

/* The adapters as an Api, for the FMI 3.0 functions in g3. The functions that only the
 * benchmark or the loading call (fmi2GetTypesPlatform, fmi2GetVersion, fmi2GetInteger,
 * fmi2SetRealInputDerivatives, fmi2GetBooleanStatus) have none: NULL. */
static void adapt_api3(Api *api) {
    *api = (Api){
        .Instantiate = a3_instantiate,
        .FreeInstance = a3_free_instance,
        .SetDebugLogging = a3_set_debug_logging,
        .SetupExperiment = a3_setup_experiment,
        .EnterInitializationMode = a3_enter_initialization_mode,
        .ExitInitializationMode = a3_exit_initialization_mode,
        .Terminate = a3_terminate,
        .Reset = a3_reset,
        .GetReal = a3_get_real,
        .SetReal = a3_set_real,
        .SetInteger = a3_set_integer,
        .GetFMUstate = a3_get_fmu_state,
        .SetFMUstate = a3_set_fmu_state,
        .FreeFMUstate = a3_free_fmu_state,
        .SerializedFMUstateSize = a3_serialized_fmu_state_size,
        .SerializeFMUstate = a3_serialize_fmu_state,
        .DeSerializeFMUstate = a3_deserialize_fmu_state,
        .DoStep = a3_do_step,
        .GetRealStatus = a3_get_real_status,
        .EnterEventMode = a3_enter_event_mode,
        .NewDiscreteStates = a3_new_discrete_states,
        .EnterContinuousTimeMode = a3_enter_continuous_time_mode,
        .CompletedIntegratorStep = a3_completed_integrator_step,
        .SetTime = a3_set_time,
        .SetContinuousStates = a3_set_continuous_states,
        .GetDerivatives = a3_get_derivatives,
        .GetEventIndicators = a3_get_event_indicators,
        .GetContinuousStates = a3_get_continuous_states,
        .GetNominalsOfContinuousStates = a3_get_nominals,
    };
}

/* Loads the functions of the FMI version the checks run through into *api (with fmi3, the
 * adapters, and the FMI 3.0 functions into g3 and *api3); the FMI 2.0 functions into *api2,
 * which the library exports in both archives. */
static int load_apis(Lib lib, int fmi3, const Model *m, Api *api, Api *api2, Err *err) {
    if (load_api(lib, api2, err)) return -1;
    if (!fmi3) {
        *api = *api2;
        return 0;
    }
    if (load_api3(lib, &g3.f, err)) return -1;
    g3.time = m->time;
    adapt_api3(api);
    return 0;
}

/* Everything an instance needs from the host. */
typedef struct {
    const Api *api;
    const Model *model;
    const char *resources; /* the FMU's resources folder: a file URI (FMI 2.0), a path (3.0) */
} Host;

/* The callbacks: the memory functions are given although canNotUseMemoryManagementFunctions is
 * true (a host may always pass them; the FMU must not call them). */
static fmi2Component instantiate(const Host *h, LogCtx *ctx, fmi2CallbackFunctions *cb,
                                 const char *guid, fmi2Type type, fmi2Boolean logging_on) {
    /* the FMU keeps a pointer to the callbacks: they live as long as the instance */
    *cb = (fmi2CallbackFunctions){logger, calloc, free, NULL, ctx};
    return h->api->Instantiate(ctx->name, type, guid, h->resources, cb, fmi2False, logging_on);
}

/* ----- 1 and 3: the paper's scene ----------------------------------------------------------- */

typedef struct {
    double phi_end, ei; /* NAN: the FMU's start value */
} SceneCfg;

#define N_POINTS (N_STEPS + 1)
typedef struct {
    double v1[N_POINTS], theta1[N_POINTS], u2[N_POINTS];
} Traj;

/* --save-state and --resume: only the paper's scene of check 1 uses them. */
typedef struct {
    int save_step;           /* -1: none; else save the state after this communication step */
    const char *save_file;   /* where the serialized state goes */
    const char *resume_file; /* NULL: start at t = 0; else restore this state first */
    int first;               /* out: the first communication step of the run (0 or resumed) */
    size_t saved_bytes, resumed_bytes; /* out: the sizes of the serialized states */
} StateIO;

/* Takes the instance's state, writes its serialization to io->save_file and frees it. */
static int save_state(const Host *h, fmi2Component c, LogCtx *lc, StateIO *io, Err *err) {
    const Api *f = h->api;
    const char *who = lc->name;
    fmi2FMUstate s = NULL;
    char *bytes = NULL;
    size_t size = 0;
    FILE *out_file = NULL;
    int rc = -1;
    OK(f->GetFMUstate(c, &s));
    OK(f->SerializedFMUstateSize(c, s, &size));
    if (size == 0 || size > (1u << 24)) {
        fail(err, "%s: serialized size %zu is implausible", who, size);
        goto out;
    }
    if (!(bytes = malloc(size))) {
        fail(err, "out of memory");
        goto out;
    }
    OK(f->SerializeFMUstate(c, s, bytes, size));
    /* binary mode: no newline translation on Windows */
    if (!(out_file = fopen(io->save_file, "wb")) || fwrite(bytes, 1, size, out_file) != size) {
        fail(err, "%s: cannot write %s", who, io->save_file);
        goto out;
    }
    io->saved_bytes = size;
    rc = 0;
out:
    if (out_file && fclose(out_file) != 0 && rc == 0)
        rc = fail(err, "cannot write %s", io->save_file);
    if (s) f->FreeFMUstate(c, &s);
    free(bytes);
    return rc;
}

/* Restores the state serialized in io->resume_file into the (initialized) instance; its
 * communication step into *step. */
static int resume_state(const Host *h, fmi2Component c, LogCtx *lc, StateIO *io, int *step,
                        Err *err) {
    const Api *f = h->api;
    const char *who = lc->name;
    fmi2FMUstate s = NULL;
    size_t size = 0;
    int rc = -1;
    char *bytes = read_file(io->resume_file, &size);
    if (!bytes) return fail(err, "%s: cannot read %s", who, io->resume_file);
    OK(f->DeSerializeFMUstate(c, bytes, size, &s));
    OK(f->SetFMUstate(c, s));
    fmi2Real t = NAN;
    OK(f->GetRealStatus(c, fmi2LastSuccessfulTime, &t));
    double k = round(t / H);
    if (!(k >= 0 && k <= N_STEPS && fabs(t - k * H) <= 1e-9)) {
        fail(err, "%s: the state of %s is at t = %.17g, not at a communication point", who,
             io->resume_file, t);
        goto out;
    }
    *step = (int)k;
    io->resumed_bytes = size;
    rc = 0;
out:
    if (s) f->FreeFMUstate(c, &s);
    free(bytes);
    return rc;
}

/* Instantiates, runs the scene with `cfg`, records the outputs at every communication point
 * (all must be finite), terminates and frees. With `io` (else NULL), first restores a state
 * and/or saves one on the way (see StateIO); points before the first step stay 0. */
static int run_scene(const Host *h, const char *name, const SceneCfg *cfg, StateIO *io,
                     Traj *out, Err *err) {
    const Api *f = h->api;
    const Model *m = h->model;
    const char *who = name;
    LogCtx ctx, *lc = &ctx;
    fmi2CallbackFunctions cb;
    ctx_init(&ctx, name);
    fmi2Component c = instantiate(h, &ctx, &cb, m->guid, fmi2CoSimulation, fmi2False);
    if (!c) return fail(err, "%s: fmi2Instantiate returned NULL (%s)", name, ctx.last);

    int rc = -1, first = 0;
    const fmi2ValueReference out_vr[3] = {m->v1, m->theta1, m->u2};
    const fmi2Integer law = PHI_SOURCE_LAW;
    double y[3];
    /* tolerance undefined: the FMU's default (the DefaultExperiment's 1e-6) */
    OK(f->SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, T_END));
    OK(f->SetInteger(c, &m->phi_source, 1, &law));
    if (!isnan(cfg->phi_end)) OK(f->SetReal(c, &m->phi_end, 1, &cfg->phi_end));
    if (!isnan(cfg->ei)) OK(f->SetReal(c, &m->ei, 1, &cfg->ei));
    OK(f->EnterInitializationMode(c));
    OK(f->ExitInitializationMode(c));
    if (io && io->resume_file && resume_state(h, c, lc, io, &first, err)) goto out;
    if (io) io->first = first;
    for (int k = first; k <= N_STEPS; k++) {
        if (k > first) OK(f->DoStep(c, (k - 1) * H, H, fmi2True));
        OK(f->GetReal(c, out_vr, 3, y));
        if (!isfinite(y[0]) || !isfinite(y[1]) || !isfinite(y[2])) {
            fail(err, "%s: non-finite output at t = %g: v1 = %g, theta1 = %g, u2 = %g", name,
                 k * H, y[0], y[1], y[2]);
            goto out;
        }
        out->v1[k] = y[0];
        out->theta1[k] = y[1];
        out->u2[k] = y[2];
        if (io && k == io->save_step && save_state(h, c, lc, io, err)) goto out;
    }
    fmi2Real t_last = NAN;
    OK(f->GetRealStatus(c, fmi2LastSuccessfulTime, &t_last));
    if (fabs(t_last - T_END) > 1e-9) {
        fail(err, "%s: fmi2LastSuccessfulTime = %.17g after the last step, expected %g", name,
             t_last, T_END);
        goto out;
    }
    OK(f->Terminate(c));
    rc = 0;
out:
    f->FreeInstance(c);
    if (rc == 0 && (ctx.count[fmi2Warning] || ctx.count[fmi2Discard] || ctx.count[fmi2Error]))
        rc = fail(err, "%s: the FMU logged warnings or errors: %s", name, ctx.last);
    return rc;
}

/* FNV-1a over the bytes of v1, theta1 and u2 from point `first` on: a compact fingerprint for
 * the summary (for first = 0, that of all the trajectory's bytes in memory order). */
static uint64_t fingerprint(const Traj *t, int first) {
    const double *parts[3] = {t->v1, t->theta1, t->u2};
    uint64_t hash = 0xcbf29ce484222325u;
    for (int j = 0; j < 3; j++) {
        const unsigned char *p = (const unsigned char *)(parts[j] + first);
        for (size_t k = 0; k < (size_t)(N_POINTS - first) * sizeof(double); k++)
            hash = (hash ^ p[k]) * 0x100000001b3u;
    }
    return hash;
}

static uint64_t bits(double x) {
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static int check_scene(const Host *h, const char *out_csv, StateIO *io, Err *err) {
    static Traj t; /* 24 kB: keep it off the stack */
    const SceneCfg paper = {NAN, NAN};
    double t0 = now();
    if (run_scene(h, "paper", &paper, io, &t, err)) return -1;
    double dt = now() - t0;
    int first = io->first;
    if (io->save_step >= 0 && io->saved_bytes == 0)
        return fail(err, "--save-state %d: the run started at step %d, after it", io->save_step,
                    first);

    double max_v1 = 0.0, max_theta1 = 0.0, max_u2 = 0.0;
    for (int k = first; k < N_POINTS; k++) {
        max_v1 = fmax(max_v1, fabs(t.v1[k]));
        max_theta1 = fmax(max_theta1, fabs(t.theta1[k]));
        max_u2 = fmax(max_u2, fabs(t.u2[k]));
    }
    if (io->resume_file)
        printf("resume file=%s bytes=%zu step=%d t=%.17g\n", io->resume_file, io->resumed_bytes,
               first, first * H);
    if (io->save_step >= 0)
        printf("save_state file=%s bytes=%zu step=%d t=%.17g\n", io->save_file, io->saved_bytes,
               io->save_step, io->save_step * H);
    printf("scene points=%d first=%d h=%g t_end=%g seconds=%.3f\n", N_POINTS - first, first, H,
           T_END, dt);
    printf("scene_final v1=%.17g theta1=%.17g u2=%.17g\n", t.v1[N_STEPS], t.theta1[N_STEPS],
           t.u2[N_STEPS]);
    printf("scene_max_abs v1=%.17g theta1=%.17g u2=%.17g\n", max_v1, max_theta1, max_u2);
    printf("scene fingerprint=%016llx\n", (unsigned long long)fingerprint(&t, first));

    if (out_csv) {
        /* binary mode: the same bytes on every platform (no \r\n on Windows) */
        FILE *f = fopen(out_csv, "wb");
        if (!f) return fail(err, "cannot write %s", out_csv);
        fprintf(f, "t,v1,theta1,u2,v1_bits,theta1_bits,u2_bits\n");
        for (int k = first; k < N_POINTS; k++)
            fprintf(f, "%.17g,%.17g,%.17g,%.17g,%016llx,%016llx,%016llx\n", k * H, t.v1[k],
                    t.theta1[k], t.u2[k], (unsigned long long)bits(t.v1[k]),
                    (unsigned long long)bits(t.theta1[k]), (unsigned long long)bits(t.u2[k]));
        if (fclose(f) != 0) return fail(err, "cannot write %s", out_csv);
    }
    return 0;
}

/* ----- 4: Model Exchange -------------------------------------------------------------------- */

#define NX 6      /* continuous states: v1, theta1, dv1, dtheta1 and the two of the filter of phi
                   (the model description's) */
#define NZ 2      /* event indicators: the margins of the range of validity */
#define ME_H 5e-4 /* the host's Runge-Kutta step; H = 20 of them, t_rot = 0.85 s = 1700 */
#define ME_PER_POINT 20
#define ME_SAVE_POINT 510 /* t = 5.1 s */

/* x' = f(t, x) through the FMU. */
static int me_rhs(const Host *h, fmi2Component c, LogCtx *lc, double t, const double *x,
                  double *dx, Err *err) {
    const Api *f = h->api;
    const char *who = lc->name;
    OK(f->SetTime(c, t));
    OK(f->SetContinuousStates(c, x, NX));
    OK(f->GetDerivatives(c, dx, NX));
    return 0;
out:
    return -1;
}

/* The event iteration at the current time; the next time event into *t_event (NAN: none). */
static int me_event(const Host *h, fmi2Component c, LogCtx *lc, double *t_event, Err *err) {
    const Api *f = h->api;
    const char *who = lc->name;
    fmi2EventInfo info = {fmi2True, 0, 0, 0, 0, 0.0};
    for (int pass = 0; info.newDiscreteStatesNeeded; pass++) {
        if (pass == 10) return fail(err, "%s: the event iteration does not end", who);
        OK(f->NewDiscreteStates(c, &info));
        if (info.terminateSimulation) return fail(err, "%s: terminateSimulation at an event", who);
    }
    *t_event = info.nextEventTimeDefined ? info.nextEventTime : NAN;
    OK(f->EnterContinuousTimeMode(c));
    return 0;
out:
    return -1;
}

/* Integrates from step k0 to k1 (t = k*ME_H; the time event lands exactly on *t_event), the
 * outputs at every communication point into `out`. A state at ME_SAVE_POINT goes to `save`
 * (a malloc'ed buffer and its size) when `save` is not NULL. */
static int me_integrate(const Host *h, fmi2Component c, LogCtx *lc, int k0, int k1,
                        double *t_event, Traj *out, char **save, size_t *save_size,
                        long *events, Err *err) {
    const Api *f = h->api;
    const Model *m = h->model;
    const char *who = lc->name;
    const fmi2ValueReference out_vr[3] = {m->v1, m->theta1, m->u2};
    double x[NX], k1v[NX], k2v[NX], k3v[NX], k4v[NX], xs[NX], z[NZ], y[3];
    fmi2FMUstate s = NULL;
    int rc = -1;
    OK(f->GetContinuousStates(c, x, NX));
    for (int k = k0 + 1; k <= k1; k++) {
        double t0 = (k - 1) * ME_H, t1 = k * ME_H;
        int event = !isnan(*t_event) && fabs(t1 - *t_event) < 0.5 * ME_H;
        if (event) t1 = *t_event;
        double hs = t1 - t0;
        if (me_rhs(h, c, lc, t0, x, k1v, err)) goto out;
        for (int i = 0; i < NX; i++) xs[i] = x[i] + 0.5 * hs * k1v[i];
        if (me_rhs(h, c, lc, t0 + 0.5 * hs, xs, k2v, err)) goto out;
        for (int i = 0; i < NX; i++) xs[i] = x[i] + 0.5 * hs * k2v[i];
        if (me_rhs(h, c, lc, t0 + 0.5 * hs, xs, k3v, err)) goto out;
        for (int i = 0; i < NX; i++) xs[i] = x[i] + hs * k3v[i];
        if (me_rhs(h, c, lc, t1, xs, k4v, err)) goto out;
        for (int i = 0; i < NX; i++)
            x[i] += hs / 6.0 * (k1v[i] + 2.0 * k2v[i] + 2.0 * k3v[i] + k4v[i]);
        OK(f->SetTime(c, t1));
        OK(f->SetContinuousStates(c, x, NX));
        fmi2Boolean enter = -1, terminate = -1;
        OK(f->CompletedIntegratorStep(c, fmi2True, &enter, &terminate));
        if (enter != fmi2False || terminate != fmi2False) {
            fail(err, "%s: fmi2CompletedIntegratorStep at t = %g: enterEventMode = %d, "
                      "terminateSimulation = %d", who, t1, enter, terminate);
            goto out;
        }
        OK(f->GetEventIndicators(c, z, NZ));
        if (!(z[0] > 0.0 && z[1] > 0.0)) {
            fail(err, "%s: an event indicator crossed zero at t = %g: %g, %g", who, t1, z[0], z[1]);
            goto out;
        }
        if (event) {
            OK(f->EnterEventMode(c));
            if (me_event(h, c, lc, t_event, err)) goto out;
            ++*events;
        }
        if (k % ME_PER_POINT == 0) {
            int p = k / ME_PER_POINT;
            OK(f->GetReal(c, out_vr, 3, y));
            if (!isfinite(y[0]) || !isfinite(y[1]) || !isfinite(y[2])) {
                fail(err, "%s: non-finite output at t = %g", who, t1);
                goto out;
            }
            out->v1[p] = y[0], out->theta1[p] = y[1], out->u2[p] = y[2];
            if (save && p == ME_SAVE_POINT) {
                OK(f->GetFMUstate(c, &s));
                OK(f->SerializedFMUstateSize(c, s, save_size));
                if (!(*save = malloc(*save_size))) {
                    fail(err, "out of memory");
                    goto out;
                }
                OK(f->SerializeFMUstate(c, s, *save, *save_size));
                OK(f->FreeFMUstate(c, &s));
            }
        }
    }
    rc = 0;
out:
    if (s) f->FreeFMUstate(c, &s);
    return rc;
}

/* A Model Exchange instance of the paper's scene (the law), initialized, in event mode. */
static fmi2Component me_start(const Host *h, LogCtx *lc, fmi2CallbackFunctions *cb, Err *err) {
    const Api *f = h->api;
    const Model *m = h->model;
    const char *who = lc->name;
    const fmi2Integer law = PHI_SOURCE_LAW;
    fmi2Component c = instantiate(h, lc, cb, m->guid, fmi2ModelExchange, fmi2False);
    if (!c) {
        fail(err, "%s: fmi2Instantiate(fmi2ModelExchange) returned NULL (%s)", who, lc->last);
        return NULL;
    }
    OK(f->SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2True, T_END));
    OK(f->SetInteger(c, &m->phi_source, 1, &law));
    OK(f->EnterInitializationMode(c));
    OK(f->ExitInitializationMode(c));
    return c;
out:
    f->FreeInstance(c);
    return NULL;
}

static int check_exchange(const Host *h, const char *out_csv, Err *err) {
    static Traj a, b; /* off the stack */
    const Api *f = h->api;
    const Model *m = h->model;
    LogCtx ctx, ctx2, *lc = &ctx;
    fmi2CallbackFunctions cb, cb2;
    const char *who = "exchange";
    char *bytes = NULL;
    size_t size = 0;
    long events = 0, events2 = 0;
    fmi2FMUstate s = NULL;
    fmi2Component c2 = NULL;
    int rc = -1;
    ctx_init(&ctx, who);
    ctx_init(&ctx2, "exchange, restored");
    double t0 = now(), t_event = NAN, y[3];
    fmi2Component c = me_start(h, &ctx, &cb, err);
    if (!c) return -1;
    /* Out of sequence: co-simulation's step, and continuous states outside continuous-time
     * mode. */
    REFUSED(f->DoStep(c, 0.0, H, fmi2True));
    double x[NX] = {0}, nominal[NX];
    REFUSED(f->SetContinuousStates(c, x, NX));
    REFUSED(f->GetContinuousStates(c, x, NX + 1));
    if (me_event(h, c, lc, &t_event, err)) goto out;
    if (!(fabs(t_event - 0.85) < 1e-12)) {
        fail(err, "%s: the next time event is %g, expected t_rot = 0.85", who, t_event);
        goto out;
    }
    OK(f->GetNominalsOfContinuousStates(c, nominal, NX));
    for (int i = 0; i < NX; i++)
        if (!(nominal[i] > 0.0)) {
            fail(err, "%s: nominal %d is %g", who, i, nominal[i]);
            goto out;
        }
    const fmi2ValueReference out_vr[3] = {m->v1, m->theta1, m->u2};
    OK(f->GetReal(c, out_vr, 3, y));
    a.v1[0] = y[0], a.theta1[0] = y[1], a.u2[0] = y[2];
    if (me_integrate(h, c, lc, 0, N_STEPS * ME_PER_POINT, &t_event, &a, &bytes, &size, &events,
                     err))
        goto out;
    double seconds = now() - t0;
    OK(f->Terminate(c));
    if (!bytes || events != 1) {
        fail(err, "%s: %ld events (expected 1), state %s", who, events, bytes ? "saved" : "missing");
        goto out;
    }

    /* The state in a second instance: it continues bit for bit. */
    lc = &ctx2;
    who = ctx2.name;
    if (!(c2 = me_start(h, &ctx2, &cb2, err))) goto out;
    OK(f->DeSerializeFMUstate(c2, bytes, size, &s));
    OK(f->SetFMUstate(c2, s));
    OK(f->FreeFMUstate(c2, &s));
    double none = NAN;
    if (me_integrate(h, c2, lc, ME_SAVE_POINT * ME_PER_POINT, N_STEPS * ME_PER_POINT, &none, &b,
                     NULL, NULL, &events2, err))
        goto out;
    for (int p = ME_SAVE_POINT + 1; p < N_POINTS; p++)
        if (bits(a.v1[p]) != bits(b.v1[p]) || bits(a.theta1[p]) != bits(b.theta1[p]) ||
            bits(a.u2[p]) != bits(b.u2[p])) {
            fail(err, "%s: the restored run differs at t = %g: v1 %.17g against %.17g", who,
                 p * H, b.v1[p], a.v1[p]);
            goto out;
        }
    OK(f->Terminate(c2));
    printf("exchange points=%d h=%g steps=%d events=%ld state_bytes=%zu restored=identical "
           "seconds=%.3f\n", N_POINTS, ME_H, N_STEPS * ME_PER_POINT, events, size, seconds);
    printf("exchange_final v1=%.17g theta1=%.17g u2=%.17g\n", a.v1[N_STEPS], a.theta1[N_STEPS],
           a.u2[N_STEPS]);
    if (out_csv) {
        FILE *o = fopen(out_csv, "wb");
        if (!o) {
            fail(err, "cannot write %s", out_csv);
            goto out;
        }
        fprintf(o, "t,v1,theta1,u2,v1_bits,theta1_bits,u2_bits\n");
        for (int k = 0; k < N_POINTS; k++)
            fprintf(o, "%.17g,%.17g,%.17g,%.17g,%016llx,%016llx,%016llx\n", k * H, a.v1[k],
                    a.theta1[k], a.u2[k], (unsigned long long)bits(a.v1[k]),
                    (unsigned long long)bits(a.theta1[k]), (unsigned long long)bits(a.u2[k]));
        if (fclose(o) != 0) {
            fail(err, "cannot write %s", out_csv);
            goto out;
        }
    }
    rc = 0;
out:
    if (s) f->FreeFMUstate(c2 ? c2 : c, &s);
    free(bytes);
    f->FreeInstance(c);
    if (c2) f->FreeInstance(c2);
    if (rc == 0 && (ctx.count[fmi2Warning] || ctx.count[fmi2Discard] || ctx2.count[fmi2Warning] ||
                    ctx2.count[fmi2Discard] || ctx2.count[fmi2Error]))
        rc = fail(err, "exchange: the FMU logged warnings or errors: %s / %s", ctx.last, ctx2.last);
    return rc;
}

/* ----- 2: instantiate/free cycles ----------------------------------------------------------- */

/* setupExperiment, enter and exit initialization mode with the law (start time 0, no stop). */
#define START(c)                                                                               \
    do {                                                                                       \
        OK(f->SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0));                        \
        OK(f->SetInteger(c, &m->phi_source, 1, &law));                                         \
        OK(f->EnterInitializationMode(c));                                                     \
        OK(f->ExitInitializationMode(c));                                                      \
    } while (0)

/* Steps from step k0 to k1 (communication points k*H), the outputs at the end into y. */
static int steps(const Host *h, fmi2Component c, LogCtx *lc, int k0, int k1, double y[3],
                 Err *err) {
    const Api *f = h->api;
    const char *who = lc->name;
    const fmi2ValueReference vr[3] = {h->model->v1, h->model->theta1, h->model->u2};
    for (int k = k0; k < k1; k++) OK(f->DoStep(c, k * H, H, fmi2True));
    OK(f->GetReal(c, vr, 3, y));
    return 0;
out:
    return -1;
}

/* FMU states: get, serialize, deserialize, step on, restore, step again: the two continuations
 * must agree bit for bit; then the states are freed (and their slots set to NULL). */
static int states_round_trip(const Host *h, fmi2Component c, LogCtx *lc, Err *err) {
    const Api *f = h->api;
    const char *who = lc->name;
    fmi2FMUstate s = NULL, copy = NULL;
    double a[3], b[3];
    int rc = -1;
    char *bytes = NULL;
    size_t size = 0;
    if (steps(h, c, lc, 0, 2, a, err)) goto out;
    OK(f->GetFMUstate(c, &s));
    if (!s) {
        fail(err, "%s: fmi2GetFMUstate gave a NULL state", who);
        goto out;
    }
    OK(f->GetFMUstate(c, &s)); /* into the existing state: overwritten in place */
    OK(f->SerializedFMUstateSize(c, s, &size));
    if (size == 0 || size > (1u << 24)) {
        fail(err, "%s: serialized size %zu is implausible", who, size);
        goto out;
    }
    bytes = malloc(size);
    if (!bytes) {
        fail(err, "out of memory");
        goto out;
    }
    OK(f->SerializeFMUstate(c, s, bytes, size));
    OK(f->DeSerializeFMUstate(c, bytes, size, &copy));
    if (steps(h, c, lc, 2, 4, a, err)) goto out;
    OK(f->SetFMUstate(c, copy));
    if (steps(h, c, lc, 2, 4, b, err)) goto out;
    if (memcmp(a, b, sizeof a) != 0) {
        fail(err, "%s: a restored (deserialized) state continues differently: v1 %.17g vs %.17g", who,
             a[0], b[0]);
        goto out;
    }
    OK(f->SetFMUstate(c, s)); /* back to t = 2H: the next caller steps from there */
    OK(f->FreeFMUstate(c, &s));
    OK(f->FreeFMUstate(c, &copy));
    if (s || copy) {
        fail(err, "%s: fmi2FreeFMUstate left a non-NULL state pointer", who);
        goto out;
    }
    rc = 0;
out:
    /* on a failure, free what is left so that valgrind reports the failure, not a leak */
    if (s) f->FreeFMUstate(c, &s);
    if (copy) f->FreeFMUstate(c, &copy);
    free(bytes);
    return rc;
}

static int one_cycle(const Host *h, int i, Err *err) {
    const Api *f = h->api;
    const Model *m = h->model;
    const fmi2Integer law = PHI_SOURCE_LAW;
    const fmi2ValueReference vr[3] = {m->v1, m->theta1, m->u2};
    char name[64];
    snprintf(name, sizeof name, "cycle%d", i);
    const char *who = name;
    LogCtx ctx, *lc = &ctx;
    fmi2CallbackFunctions cb;
    ctx_init(&ctx, name);
    double y[3] = {0.0, 0.0, 0.0};
    int rc = -1;
    fmi2Component c = NULL;

    switch (i % 8) {
    case 0: /* instantiate and free, nothing else */
    case 1:
        c = instantiate(h, &ctx, &cb, m->guid, fmi2CoSimulation, (fmi2Boolean)(i % 2));
        break;
    case 2: /* rejected instantiations: wrong GUID, an unknown fmi2Type; each logs one error */
        for (int bad = 0; bad < 2; bad++) {
            ctx.expect_errors = 1;
            fmi2Component x =
                bad == 0 ? instantiate(h, &ctx, &cb, "{not-the-guid}", fmi2CoSimulation, fmi2False)
                         : instantiate(h, &ctx, &cb, m->guid, (fmi2Type)7, fmi2False);
            ctx.expect_errors = 0;
            if (x) {
                f->FreeInstance(x);
                fail(err, "%s: fmi2Instantiate accepted a %s", name,
                     bad == 0 ? "wrong GUID" : "type that is neither interface");
                goto out;
            }
        }
        if (ctx.count[fmi2Error] != 2) {
            fail(err, "%s: %ld error messages for two refused instantiations, expected 2", name,
                 ctx.count[fmi2Error]);
            goto out;
        }
        c = instantiate(h, &ctx, &cb, m->guid, fmi2CoSimulation, fmi2False);
        break;
    default:
        c = instantiate(h, &ctx, &cb, m->guid, fmi2CoSimulation, fmi2False);
    }
    if (!c) {
        fail(err, "%s: fmi2Instantiate returned NULL (%s)", name, ctx.last);
        goto out;
    }

    switch (i % 8) {
    case 3: { /* debug logging on for every category: calls are logged at fmi2OK */
        OK(f->SetDebugLogging(c, fmi2True, 0, NULL));
        const fmi2String cats[] = {"logCalls"};
        OK(f->SetDebugLogging(c, fmi2True, 1, cats));
        START(c);
        if (steps(h, c, lc, 0, 3, y, err)) goto out;
        OK(f->Terminate(c));
        if (ctx.count[fmi2OK] == 0) {
            fail(err, "%s: logCalls is on but the FMU logged no call", name);
            goto out;
        }
        break;
    }
    case 4: /* the whole life cycle */
        START(c);
        if (steps(h, c, lc, 0, 3, y, err)) goto out;
        OK(f->Terminate(c));
        break;
    case 5: /* FMU states and their serialization */
        START(c);
        if (states_round_trip(h, c, lc, err)) goto out;
        if (steps(h, c, lc, 2, 3, y, err)) goto out;
        OK(f->Terminate(c));
        {
            /* A state the host never frees: fmi2FreeInstance frees it with the instance
             * ("frees all the allocated memory", FMI 2.0 section 2.1.5); valgrind checks. */
            fmi2FMUstate forgotten = NULL;
            OK(f->GetFMUstate(c, &forgotten));
        }
        break;
    case 6: /* calls out of sequence are refused and logged; the instance stays usable */
        REFUSED(f->DoStep(c, 0.0, H, fmi2True));
        REFUSED(f->GetReal(c, vr, 3, y));
        REFUSED(f->ExitInitializationMode(c));
        START(c);
        REFUSED(f->DoStep(c, 5.0, H, fmi2True)); /* tc is not the FMU's time */
        REFUSED(f->SetInteger(c, &m->phi_source, 1, &law)); /* fixed parameter after init */
        if (steps(h, c, lc, 0, 2, y, err)) goto out;
        OK(f->Terminate(c));
        REFUSED(f->DoStep(c, 2 * H, H, fmi2True));
        break;
    case 7: /* reset, then a second run; freed in stepComplete (no fmi2Terminate) */
        START(c);
        if (steps(h, c, lc, 0, 2, y, err)) goto out;
        OK(f->Reset(c));
        START(c);
        if (steps(h, c, lc, 0, 1, y, err)) goto out;
        break;
    default:
        break;
    }
    if (!isfinite(y[0]) || !isfinite(y[1]) || !isfinite(y[2])) {
        fail(err, "%s: non-finite v1", name);
        goto out;
    }
    rc = 0;
out:
    if (c) f->FreeInstance(c);
    return rc;
}

static int check_cycles(const Host *h, int n, Err *err) {
    double t0 = now();
    long before = atomic_load(&g_messages);
    for (int i = 0; i < n; i++)
        if (one_cycle(h, i, err)) return -1;
    printf("cycles n=%d messages=%ld seconds=%.3f\n", n, atomic_load(&g_messages) - before,
           now() - t0);
    return 0;
}

/* ----- 3: concurrent instances -------------------------------------------------------------- */

typedef struct {
    const Host *host;
    Gate *start;
    int index;
    SceneCfg cfg;
    Traj traj;
    Err err;
    int rc;
} Job;

static SceneCfg thread_cfg(int i) {
    /* each thread its own turn angle and stiffness, so that the results differ */
    SceneCfg cfg = {PI * (1.0 - i / 16.0), 1000.0 * (1.0 + i / 8.0)};
    return cfg;
}

static ThreadResult THREAD_CALL thread_main(void *arg) {
    Job *job = arg;
    char name[64];
    snprintf(name, sizeof name, "thread%d", job->index);
    /* all threads start together, so that their instantiations and steps overlap */
    gate_wait(job->start);
    job->rc = run_scene(job->host, name, &job->cfg, NULL, &job->traj, &job->err);
    return 0;
}

static int check_threads(const Host *h, int n, Err *err) {
    Job *jobs = calloc((size_t)n, sizeof *jobs);
    Traj *ref = calloc((size_t)n, sizeof *ref);
    Thread *tid = calloc((size_t)n, sizeof *tid);
    int rc = -1, started = 0;
    Gate start;
    int gate = 0;
    if (!jobs || !ref || !tid) {
        fail(err, "out of memory");
        goto out;
    }
    /* the reference: the same configurations one after another, in this thread */
    double t0 = now();
    for (int i = 0; i < n; i++) {
        char name[64];
        snprintf(name, sizeof name, "sequential%d", i);
        SceneCfg cfg = thread_cfg(i);
        if (run_scene(h, name, &cfg, NULL, &ref[i], err)) goto out;
    }
    double t_seq = now() - t0;

    if (gate_init(&start, (unsigned)n)) {
        fail(err, "cannot create the start gate (mutex, condition variable)");
        goto out;
    }
    gate = 1;
    t0 = now();
    for (int i = 0; i < n; i++) {
        jobs[i] = (Job){.host = h, .start = &start, .index = i, .cfg = thread_cfg(i), .rc = -1};
        if (thread_start(&tid[i], thread_main, &jobs[i])) {
            fail(err, "cannot start thread %d", i);
            /* the started threads wait at the gate for ever: exit without joining */
            goto out;
        }
        started++;
    }
    for (int i = 0; i < n; i++) thread_join(tid[i]);
    double t_par = now() - t0;

    int distinct = 0;
    for (int i = 0; i < n; i++) {
        if (jobs[i].rc) {
            fail(err, "thread %d: %s", i, jobs[i].err.msg);
            goto out;
        }
        if (memcmp(&jobs[i].traj, &ref[i], sizeof ref[i]) != 0) {
            int k = 0;
            while (k < N_POINTS && jobs[i].traj.v1[k] == ref[i].v1[k] &&
                   jobs[i].traj.theta1[k] == ref[i].theta1[k] && jobs[i].traj.u2[k] == ref[i].u2[k])
                k++;
            double mine = k < N_POINTS ? jobs[i].traj.v1[k] : NAN;
            double theirs = k < N_POINTS ? ref[i].v1[k] : NAN;
            fail(err, "thread %d differs from its sequential run, first at t = %g: v1 %.17g vs %.17g",
                 i, k * H, mine, theirs);
            goto out;
        }
        distinct += i == 0 || memcmp(&ref[i], &ref[i - 1], sizeof ref[i]) != 0;
    }
    if (distinct != n) {
        fail(err, "only %d of %d configurations gave distinct trajectories", distinct, n);
        goto out;
    }
    printf("threads n=%d identical=1 distinct=%d sequential_seconds=%.3f parallel_seconds=%.3f\n",
           n, distinct, t_seq, t_par);
    for (int i = 0; i < n; i++)
        printf("thread %d phi_end=%.17g EI=%.17g final_v1=%.17g fingerprint=%016llx\n", i,
               jobs[i].cfg.phi_end, jobs[i].cfg.ei, jobs[i].traj.v1[N_STEPS],
               (unsigned long long)fingerprint(&jobs[i].traj, 0));
    rc = 0;
out:
    if (started < n && started > 0) {
        fprintf(stderr, "host: %s\n", err->msg);
        exit(1);
    }
    if (gate) gate_destroy(&start);
    free(jobs);
    free(ref);
    free(tid);
    return rc;
}

/* ----- 5 (FMI 3.0): the intermediate-update callback ---------------------------------------- */

#define IU_H 0.0085     /* the communication step: the DefaultExperiment's stepSize */
#define IU_DT 1e-3      /* intermediate_step */
#define IU_STEPS 200    /* t = 0 .. 1.7 s = 2 t_rot: the turn, and as long again after it */
#define IU_RTOL 1e-8    /* the tolerance of the three runs (see check_intermediate) */
#define IU_TOL 1e-5     /* max |v1 - v1 of the law's run| [m] */
#define IU_MAX_CALLS 64 /* callbacks recorded in one step */

/* The paper's law, phi = pi sin^2(pi t / (2 t_rot)) for t < t_rot = 0.85 s, then pi, as a host
 * computes it: with the C library's sin (the FMU's law uses its own). */
static double paper_phi(double t) {
    if (t >= 0.85) return PI;
    double s = sin(PI * t / (2.0 * 0.85));
    return PI * s * s;
}

/* The instance environment of check 5: the logger's context first (the logger takes the
 * environment as a LogCtx), then what the intermediate-update callback needs and records. */
typedef struct {
    LogCtx log;
    const Api3 *f;
    const Model *m;
    fmi3Instance inst;
    int n;                      /* callbacks in the current step */
    double times[IU_MAX_CALLS]; /* their intermediateUpdateTime */
    long bad;                   /* callbacks that found something wrong; the first's reason: */
    char why[512];
} IuEnv;

/* Sets phi to the law at the time given; checks the flags and that `time` reads that time. */
static void intermediate_update(fmi3InstanceEnvironment env, fmi3Float64 t,
                                fmi3Boolean set_requested, fmi3Boolean get_allowed,
                                fmi3Boolean step_finished, fmi3Boolean can_return_early,
                                fmi3Boolean *early, fmi3Float64 *early_time) {
    IuEnv *e = env;
    (void)step_finished; /* the FMU's parts are its own steps: either value is right */
    if (e->n < IU_MAX_CALLS) e->times[e->n] = t;
    e->n++;
    char why[400] = "";
    double phi = paper_phi(t), now_t = NAN;
    if (!set_requested || !get_allowed || can_return_early || !early || !early_time)
        snprintf(why, sizeof why,
                 "intermediateVariableSetRequested = %d, intermediateVariableGetAllowed = %d, "
                 "canReturnEarly = %d, earlyReturnRequested %s, earlyReturnTime %s",
                 set_requested, get_allowed, can_return_early, early ? "given" : "NULL",
                 early_time ? "given" : "NULL");
    else if (e->f->SetFloat64(e->inst, &e->m->phi, 1, &phi, 1) != fmi3OK)
        snprintf(why, sizeof why, "fmi3SetFloat64(phi = %.17g) failed: %s", phi, e->log.last);
    else if (e->f->GetFloat64(e->inst, &e->m->time, 1, &now_t, 1) != fmi3OK || !(now_t == t))
        snprintf(why, sizeof why, "`time` reads %.17g (%s)", now_t, e->log.last);
    if (why[0] && e->bad++ == 0)
        snprintf(e->why, sizeof e->why, "the callback at t = %.17g: %s", t, why);
}

/* The ends of the parts of a step by h from the FMU's time `from` to `target` = tc + h, but the
 * last's, by the FMU's rule (src/fmi/cosim.rs, step_part): intermediate_step dt (at least
 * h/100) while more than 1.25 dt remains, then the rest. Their number (the callbacks of the
 * step); the first `cap` into `ends`. */
static int iu_rule(double from, double target, double h, double dt, double *ends, int cap) {
    int n = 0;
    dt = fmax(dt, h / 100.0);
    while (from + 1.25 * dt < target && from + dt > from) {
        from += dt;
        if (n < cap) ends[n] = from;
        n++;
    }
    return n;
}

enum { IU_LAW, IU_VALUES, IU_CALLBACK, N_IU_RUNS };
static const char *const IU_RUNS[N_IU_RUNS] = {"law", "values", "intermediate"};

typedef struct {
    double v1[IU_STEPS + 1];
    long calls, expected;
    int per_step_min, per_step_max;
} IuRun;

/* One run of IU_STEPS steps of IU_H: phi from the law (IU_LAW), from the host at the
 * communication points only (IU_VALUES), or also from the callback inside the steps. */
static int iu_run(const Api3 *f, const Model *m, const char *resources, int mode, IuRun *out,
                  Err *err) {
    IuEnv e;
    memset(&e, 0, sizeof e);
    ctx_init(&e.log, IU_RUNS[mode]);
    e.f = f, e.m = m;
    LogCtx *lc = &e.log;
    const char *who = e.log.name;
    const int cb = mode == IU_CALLBACK;
    const fmi3ValueReference required[1] = {m->phi};
    fmi3Instance c = f->InstantiateCoSimulation(
        who, m->guid, resources, fmi3False, fmi3False, fmi3False, fmi3False, cb ? required : NULL,
        cb ? 1 : 0, &e, logger3, cb ? intermediate_update : NULL);
    if (!c) return fail(err, "%s: fmi3InstantiateCoSimulation returned NULL (%s)", who, e.log.last);
    e.inst = c;
    int rc = -1;
    const fmi3Int64 source = mode == IU_LAW ? PHI_SOURCE_LAW : PHI_SOURCE_INPUT;
    const double dt = IU_DT;
    double phi = paper_phi(0.0), fmu_time = 0.0, ends[IU_MAX_CALLS];
    OK(f->SetInt64(c, &m->phi_source, 1, &source, 1));
    if (cb) OK(f->SetFloat64(c, &m->intermediate_step, 1, &dt, 1));
    if (mode != IU_LAW) OK(f->SetFloat64(c, &m->phi, 1, &phi, 1));
    OK(f->EnterInitializationMode(c, fmi3True, IU_RTOL, 0.0, fmi3False, 0.0));
    OK(f->ExitInitializationMode(c));
    OK(f->GetFloat64(c, &m->v1, 1, &out->v1[0], 1));
    out->calls = out->expected = 0;
    out->per_step_min = 1 << 30, out->per_step_max = 0;
    for (int k = 1; k <= IU_STEPS; k++) {
        const double tc = (k - 1) * IU_H;
        bool event = true, terminate = true, early = true;
        double last = NAN;
        if (mode != IU_LAW) {
            phi = paper_phi(tc);
            OK(f->SetFloat64(c, &m->phi, 1, &phi, 1));
        }
        e.n = 0;
        OK(f->DoStep(c, tc, IU_H, fmi3True, &event, &terminate, &early, &last));
        if (event || terminate || early || !(last == tc + IU_H)) {
            fail(err, "%s: fmi3DoStep(%.17g, %g): eventHandlingNeeded = %d, terminateSimulation "
                      "= %d, earlyReturn = %d, lastSuccessfulTime = %.17g",
                 who, tc, IU_H, event, terminate, early, last);
            goto out;
        }
        int want = cb ? iu_rule(fmu_time, tc + IU_H, IU_H, dt, ends, IU_MAX_CALLS) : 0;
        if (e.n != want) {
            fail(err, "%s: %d callbacks in the step from t = %.17g, the rule gives %d", who, e.n,
                 tc, want);
            goto out;
        }
        for (int j = 0; j < want && j < IU_MAX_CALLS; j++)
            if (!(e.times[j] == ends[j])) {
                fail(err, "%s: callback %d of the step from t = %.17g at t = %.17g, the rule "
                          "gives %.17g",
                     who, j, tc, e.times[j], ends[j]);
                goto out;
            }
        out->calls += e.n, out->expected += want;
        if (e.n < out->per_step_min) out->per_step_min = e.n;
        if (e.n > out->per_step_max) out->per_step_max = e.n;
        fmu_time = last;
        OK(f->GetFloat64(c, &m->v1, 1, &out->v1[k], 1));
        if (!isfinite(out->v1[k])) {
            fail(err, "%s: v1 = %g at t = %g", who, out->v1[k], k * IU_H);
            goto out;
        }
    }
    if (e.bad) {
        fail(err, "%s: %ld callbacks went wrong; %s", who, e.bad, e.why);
        goto out;
    }
    OK(f->Terminate(c));
    rc = 0;
out:
    f->FreeInstance(c);
    if (rc == 0 && (e.log.count[fmi3Warning] || e.log.count[fmi3Discard] || e.log.count[fmi3Error]))
        rc = fail(err, "%s: the FMU logged warnings or errors: %s", who, e.log.last);
    return rc;
}

/* The three runs at tolerance IU_RTOL, so that their difference is the host's phi against the
 * law's rather than the integrator's error (at the default 1e-6: 6.0e-5 m in v1; at 1e-8:
 * 2.2e-6 m, against 2.4e-4 m with phi at the communication points only). */
static int check_intermediate(const Api3 *f, const Model *m, const char *resources, Err *err) {
    static IuRun runs[N_IU_RUNS];
    double t0 = now();
    for (int mode = 0; mode < N_IU_RUNS; mode++)
        if (iu_run(f, m, resources, mode, &runs[mode], err)) return -1;
    double seconds = now() - t0, d = 0.0, d_values = 0.0;
    const IuRun *law = &runs[IU_LAW], *iu = &runs[IU_CALLBACK];
    for (int k = 0; k <= IU_STEPS; k++) {
        d = fmax(d, fabs(iu->v1[k] - law->v1[k]));
        d_values = fmax(d_values, fabs(runs[IU_VALUES].v1[k] - law->v1[k]));
    }
    if (iu->calls == 0) return fail(err, "intermediate: the callback was never called");
    if (!(d < IU_TOL))
        return fail(err, "intermediate: max |v1 - v1 of the law's run| = %.3e m > %g", d, IU_TOL);
    if (!(d < d_values))
        return fail(err, "intermediate: max |v1 - law's| = %.3e m, not below the run with phi "
                         "at the communication points only, %.3e m",
                    d, d_values);
    printf("intermediate steps=%d h=%g intermediate_step=%g rtol=%g callbacks=%ld expected=%ld "
           "per_step_min=%d per_step_max=%d max_dv1=%.3e max_dv1_values_only=%.3e seconds=%.3f\n",
           IU_STEPS, IU_H, IU_DT, IU_RTOL, iu->calls, iu->expected, iu->per_step_min,
           iu->per_step_max, d, d_values, seconds);
    printf("intermediate_final t=%.17g v1=%.17g law_v1=%.17g\n", IU_STEPS * IU_H,
           iu->v1[IU_STEPS], law->v1[IU_STEPS]);
    return 0;
}

/* ----- 7 (FMI 3.0): arrays sized by a structural parameter ---------------------------------- */

#define ARR_N 4       /* elements of the co-simulation run */
#define ARR_N_ME 2    /* elements of the Model Exchange instance */
#define ARR_STEPS 100 /* steps of H */

/* Co-simulation of the beam in ARR_N elements (n_elements set in configuration mode): after
 * every step nodal_v, read with nValues = ARR_N, is finite and ends in v1 (the tip last), and
 * nValues = ARR_N - 1 is refused; Model Exchange in ARR_N_ME elements has 4 ARR_N_ME + 2 states,
 * whose derivatives are finite. */
static int check_arrays(const Api3 *f, const Model *m, const char *resources, Err *err) {
    const char *who = "arrays";
    LogCtx ctx, *lc = &ctx;
    ctx_init(&ctx, who);
    int rc = -1;
    const fmi3Int64 law = PHI_SOURCE_LAW;
    const uint64_t n = ARR_N, n_me = ARR_N_ME;
    double v[ARR_N + 1], v1 = NAN, t = 0.0, bend = 0.0;
    double x[4 * ARR_N_ME + 2], dx[4 * ARR_N_ME + 2];
    bool a = false, b = false, d = false, flags[4];
    size_t nx = 0;
    fmi3Instance me = NULL;
    fmi3Instance c = f->InstantiateCoSimulation(who, m->guid, resources, fmi3False, fmi3False,
                                                fmi3False, fmi3False, NULL, 0, &ctx, logger3, NULL);
    if (!c) return fail(err, "%s: fmi3InstantiateCoSimulation returned NULL (%s)", who, ctx.last);
    OK(f->EnterConfigurationMode(c));
    OK(f->SetUInt64(c, &m->n_elements, 1, &n, 1));
    OK(f->ExitConfigurationMode(c));
    OK(f->SetInt64(c, &m->phi_source, 1, &law, 1));
    OK(f->EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3True, T_END));
    OK(f->ExitInitializationMode(c));
    for (int k = 0; k < ARR_STEPS; k++) {
        OK(f->DoStep(c, k * H, H, fmi3True, &a, &b, &d, &t));
        v[ARR_N] = 12345.0; /* a canary past the array: never written */
        OK(f->GetFloat64(c, &m->nodal_v, 1, v, ARR_N));
        OK(f->GetFloat64(c, &m->v1, 1, &v1, 1));
        for (int j = 0; j < ARR_N; j++)
            if (!isfinite(v[j])) {
                fail(err, "%s: nodal_v[%d] = %g at t = %g", who, j, v[j], t);
                goto out;
            }
        if (bits(v[ARR_N - 1]) != bits(v1) || v[ARR_N] != 12345.0) {
            fail(err, "%s: at t = %g nodal_v ends in %.17g, v1 = %.17g (canary %g)", who, t,
                 v[ARR_N - 1], v1, v[ARR_N]);
            goto out;
        }
        bend = fmax(bend, fabs(v1));
    }
    REFUSED(f->GetFloat64(c, &m->nodal_v, 1, v, ARR_N - 1));
    OK(f->Terminate(c));

    me = f->InstantiateModelExchange(who, m->guid, resources, fmi3False, fmi3False, &ctx, logger3);
    if (!me) {
        fail(err, "%s: fmi3InstantiateModelExchange returned NULL (%s)", who, ctx.last);
        goto out;
    }
    OK(f->EnterConfigurationMode(me));
    OK(f->SetUInt64(me, &m->n_elements, 1, &n_me, 1));
    OK(f->ExitConfigurationMode(me));
    OK(f->SetInt64(me, &m->phi_source, 1, &law, 1));
    OK(f->GetNumberOfContinuousStates(me, &nx));
    if (nx != 4 * ARR_N_ME + 2) {
        fail(err, "%s: %zu continuous states in %d elements, expected %d", who, nx, ARR_N_ME,
             4 * ARR_N_ME + 2);
        goto out;
    }
    OK(f->EnterInitializationMode(me, fmi3False, 0.0, 0.0, fmi3True, T_END));
    OK(f->ExitInitializationMode(me));
    OK(f->UpdateDiscreteStates(me, &flags[0], &flags[1], &flags[2], &flags[3], &a, &t));
    OK(f->EnterContinuousTimeMode(me));
    OK(f->GetContinuousStates(me, x, nx));
    OK(f->SetTime(me, 0.1));
    OK(f->SetContinuousStates(me, x, nx));
    OK(f->GetContinuousStateDerivatives(me, dx, nx));
    for (size_t j = 0; j < nx; j++)
        if (!isfinite(dx[j])) {
            fail(err, "%s: derivative %zu = %g", who, j, dx[j]);
            goto out;
        }
    printf("arrays n_elements=%d steps=%d max_abs_v1=%.6f me_n_elements=%d me_states=%zu\n", ARR_N,
           ARR_STEPS, bend, ARR_N_ME, nx);
    rc = 0;
out:
    f->FreeInstance(c);
    f->FreeInstance(me);
    if (rc == 0 && (ctx.count[fmi3Warning] || ctx.count[fmi3Discard]))
        rc = fail(err, "%s: the FMU logged warnings: %s", who, ctx.last);
    return rc;
}

/* ----- 6 (FMI 3.0): misuse ------------------------------------------------------------------ */

/* A call on a NULL instance: fmi3Error, and no message (there is no logger to send it to). */
#define REFUSED_NULL(call)                                                                     \
    do {                                                                                       \
        long before_ = atomic_load(&g_messages);                                               \
        int got_ = (int)(call);                                                                \
        long logged_ = atomic_load(&g_messages) - before_;                                     \
        if (got_ != fmi3Error || logged_ != 0) {                                               \
            fail(err, "%s: line %d: %s returned %s with %ld messages, expected fmi3Error",     \
                 who, __LINE__, #call, status_name(got_), logged_);                            \
            goto out;                                                                          \
        }                                                                                      \
        refused++;                                                                             \
    } while (0)

static int check_misuse(const Api *f2, const Api3 *f, const Model *m, const char *resources,
                        Err *err) {
    const char *who = "misuse";
    LogCtx ctx, ctx2, *lc = &ctx;
    fmi2CallbackFunctions cb2;
    ctx_init(&ctx, "misuse");
    ctx_init(&ctx2, "misuse, FMI 2.0");
    fmi3Instance c = NULL, me = NULL;
    fmi2Component c2 = NULL;
    int rc = -1, refused = 0;
    bool a = false, b = false, d = false, flags[4];
    double t = 0.0, y3 = 0.0, y2 = 0.0;
    size_t nx = 0, nz = 0;
    const fmi3Int64 law = PHI_SOURCE_LAW;
    const fmi2Integer law2 = PHI_SOURCE_LAW;

    /* A NULL instance. */
    REFUSED_NULL(f->DoStep(NULL, 0.0, H, fmi3True, &a, &b, &d, &t));
    REFUSED_NULL(f->GetFloat64(NULL, &m->v1, 1, &y3, 1));
    REFUSED_NULL(f->EnterInitializationMode(NULL, fmi3False, 0.0, 0.0, fmi3False, 0.0));
    REFUSED_NULL(f->Terminate(NULL));
    f->FreeInstance(NULL); /* ignored */

    /* Scheduled execution, which this FMU does not provide: NULL, and one error. */
    ctx.expect_errors = 1;
    fmi3Instance se = f->InstantiateScheduledExecution(who, m->guid, resources, fmi3False,
                                                       fmi3False, &ctx, logger3, NULL, NULL, NULL);
    ctx.expect_errors = 0;
    if (se || ctx.count[fmi3Error] != 1) {
        if (se) f->FreeInstance(se);
        fail(err, "%s: fmi3InstantiateScheduledExecution returned %p with %ld errors logged, "
                  "expected NULL and one",
             who, se, ctx.count[fmi3Error]);
        goto out;
    }
    refused++;

    /* Co-simulation: in configuration mode only the structural parameter may be set, and it
     * is left once; no event mode, no NULL out-argument. */
    c = f->InstantiateCoSimulation(who, m->guid, resources, fmi3False, fmi3False, fmi3False,
                                   fmi3False, NULL, 0, &ctx, logger3, NULL);
    if (!c) {
        fail(err, "%s: fmi3InstantiateCoSimulation returned NULL (%s)", who, ctx.last);
        goto out;
    }
    OK(f->EnterConfigurationMode(c));
    REFUSED(f->SetInt64(c, &m->phi_source, 1, &law, 1));
    OK(f->ExitConfigurationMode(c));
    REFUSED(f->ExitConfigurationMode(c));
    OK(f->SetInt64(c, &m->phi_source, 1, &law, 1));
    OK(f->EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3True, T_END));
    OK(f->ExitInitializationMode(c));
    REFUSED(f->UpdateDiscreteStates(c, &flags[0], &flags[1], &flags[2], &flags[3], &a, &t));
    REFUSED(f->DoStep(c, 0.0, H, fmi3True, &a, &b, NULL, &t));
    refused += 4;

    /* An FMI 2.0 instance of the same library: the versions do not mix, either way. */
    cb2 = (fmi2CallbackFunctions){logger, calloc, free, NULL, &ctx2};
    c2 = f2->Instantiate(ctx2.name, fmi2CoSimulation, m->guid, NULL, &cb2, fmi2False, fmi2False);
    if (!c2) {
        fail(err, "%s: fmi2Instantiate returned NULL (%s)", who, ctx2.last);
        goto out;
    }
    lc = &ctx2;
    OK(f2->SetupExperiment(c2, fmi2False, 0.0, 0.0, fmi2True, T_END));
    OK(f2->SetInteger(c2, &m->phi_source, 1, &law2));
    OK(f2->EnterInitializationMode(c2));
    OK(f2->ExitInitializationMode(c2));
    REFUSED(f->DoStep(c2, 0.0, H, fmi3True, &a, &b, &d, &t)); /* logged by the FMI 2.0 logger */
    OK(f2->DoStep(c2, 0.0, H, fmi2True));
    OK(f2->GetReal(c2, &m->v1, 1, &y2));
    lc = &ctx;
    REFUSED(f2->DoStep(c, 0.0, H, fmi2True)); /* logged by the FMI 3.0 logger */
    OK(f->DoStep(c, 0.0, H, fmi3True, &a, &b, &d, &t));
    OK(f->GetFloat64(c, &m->v1, 1, &y3, 1));
    refused += 2;
    /* both went on, and are the same model */
    if (bits(y3) != bits(y2) || y3 == 0.0) {
        fail(err, "%s: after one step v1 = %.17g through FMI 3.0, %.17g through FMI 2.0", who, y3,
             y2);
        goto out;
    }
    OK(f->Terminate(c));
    lc = &ctx2;
    OK(f2->Terminate(c2));
    lc = &ctx;

    /* Model Exchange: its sizes; co-simulation's step refused. */
    me = f->InstantiateModelExchange(who, m->guid, resources, fmi3False, fmi3False, &ctx, logger3);
    if (!me) {
        fail(err, "%s: fmi3InstantiateModelExchange returned NULL (%s)", who, ctx.last);
        goto out;
    }
    OK(f->GetNumberOfContinuousStates(me, &nx));
    OK(f->GetNumberOfEventIndicators(me, &nz));
    if (nx != NX || nz != NZ) {
        fail(err, "%s: %zu continuous states and %zu event indicators, expected %d and %d", who,
             nx, nz, NX, NZ);
        goto out;
    }
    REFUSED(f->DoStep(me, 0.0, H, fmi3True, &a, &b, &d, &t));
    refused++;
    printf("misuse refused=%d errors_logged=%ld\n", refused,
           ctx.count[fmi3Error] + ctx2.count[fmi3Error]);
    rc = 0;
out:
    f->FreeInstance(c);
    f->FreeInstance(me);
    if (c2) f2->FreeInstance(c2);
    return rc;
}

/* dlclose (FreeLibrary), then reports whether the library really left the process: glibc
 * keeps it mapped (DF_1_NODELETE) when it registered thread-local destructors, for instance. */
static int unload(Lib lib, const char *path, Err *err) {
    if (lib_close(lib)) return fail(err, "unloading %s: %s", path, lib_error());
    printf("dlclose unloaded=%d\n", !lib_loaded(path));
    return 0;
}

/* ----- 4: the cost of one fmi2DoStep (--bench-dostep) ---------------------------------------- */

/* How phi arrives: the fixed-step floor (BDF2 with h = the communication step and phi from the
 * built-in law: one internal step per communication step), the built-in law with the adaptive BDF,
 * and the input sent as values, as values with phi' and phi'' (smooth interpolation), and as values
 * with derivatives under phi_interpolation = taylor. Then the exact beam in 8 elements with the
 * law (at the 1 ms communication step only): the BDF and Radau IIA at tolerance 1e-6, and Radau at
 * 1e-4 (where 8 elements are within 1e-4 of the converged beam, docs/work_precision_exact.md). */
enum {
    FEED_FLOOR, FEED_LAW, FEED_VALUES, FEED_DERIVATIVES, FEED_TAYLOR,
    FEED_EXACT_BDF, FEED_EXACT_RADAU, FEED_EXACT_RADAU_LOOSE, N_FEEDS
};
static const char *const FEEDS[N_FEEDS] = {"floor", "law", "values", "derivatives", "taylor",
                                           "exact-bdf", "exact-radau", "exact-radau-1e-4"};
#define EXACT_H 1e-3
static const double BENCH_H[] = {1e-2, 1e-3, 1e-4};
#define N_BENCH_H (sizeof BENCH_H / sizeof BENCH_H[0])

/* The paper's law (phi_end = pi, t_rot = 0.85 s), as a host would send it. */
static void paper_law(double t, double out[3]) {
    const double t_rot = 0.85, w = PI / t_rot;
    if (t >= t_rot) {
        out[0] = PI, out[1] = 0.0, out[2] = 0.0;
        return;
    }
    out[0] = 0.5 * PI * (1.0 - cos(w * t));
    out[1] = 0.5 * PI * w * sin(w * t);
    out[2] = 0.5 * PI * w * w * cos(w * t);
}

/* One run of the paper's scene at communication step hc, rtol 1e-6: the seconds of the DoStep
 * loop (with the inputs it sets), from the first fmi2DoStep to the last. */
static int bench_case(const Host *h, int feed, double hc, double *seconds, int *steps, Err *err) {
    const Api *f = h->api;
    const Model *m = h->model;
    const char *who = FEEDS[feed];
    LogCtx ctx, *lc = &ctx;
    fmi2CallbackFunctions cb;
    ctx_init(&ctx, who);
    fmi2Component c = instantiate(h, &ctx, &cb, m->guid, fmi2CoSimulation, fmi2False);
    if (!c) return fail(err, "%s: fmi2Instantiate returned NULL (%s)", who, ctx.last);
    int rc = -1;
    double *p = NULL;
    const int n = (int)lround(T_END / hc);
    const fmi2Integer law = PHI_SOURCE_LAW, taylor = 2;
    const int exact = feed >= FEED_EXACT_BDF;
    const int input = feed >= FEED_VALUES && !exact, derivatives = input && feed >= FEED_DERIVATIVES;
    OK(f->SetupExperiment(c, fmi2True, feed == FEED_EXACT_RADAU_LOOSE ? 1e-4 : 1e-6, 0.0, fmi2True,
                          T_END));
    if (!input) OK(f->SetInteger(c, &m->phi_source, 1, &law));
    if (exact) { /* enumerations count from 1: beam quadratic, exact; integrator auto, bdf, radau */
        const fmi2Integer beam = 2, elements = 8, integrator = feed == FEED_EXACT_BDF ? 2 : 3;
        OK(f->SetInteger(c, &m->beam, 1, &beam));
        OK(f->SetInteger(c, &m->n_elements2, 1, &elements));
        OK(f->SetInteger(c, &m->integrator, 1, &integrator));
    }
    if (feed == FEED_FLOOR) OK(f->SetReal(c, &m->fixed_step, 1, &hc));
    if (feed == FEED_TAYLOR) OK(f->SetInteger(c, &m->phi_interpolation, 1, &taylor));
    OK(f->EnterInitializationMode(c));
    OK(f->ExitInitializationMode(c));
    const fmi2ValueReference two[2] = {m->phi, m->phi};
    const fmi2Integer orders[2] = {1, 2};
    /* The host's signal is computed before the clock starts: the loop times the FMU's calls. */
    if (input && !(p = malloc(sizeof(double) * 3 * (size_t)n))) {
        fail(err, "%s: out of memory", who);
        goto out;
    }
    for (int k = 0; input && k < n; k++) paper_law(k * hc, p + 3 * k);
    double t0 = now();
    for (int k = 0; k < n; k++) {
        double tc = k * hc;
        if (input) {
            OK(f->SetReal(c, &m->phi, 1, p + 3 * k));
            if (derivatives) OK(f->SetRealInputDerivatives(c, two, 2, orders, p + 3 * k + 1));
        }
        OK(f->DoStep(c, tc, hc, fmi2True));
    }
    *seconds = now() - t0;
    *steps = n;
    OK(f->Terminate(c));
    rc = 0;
out:
    free(p);
    f->FreeInstance(c);
    return rc;
}

/* ROUNDS rounds after a warm-up round 0, each running every feed at every communication step in
 * an order shuffled with the round as seed; one CSV row per run on stdout. */
static int bench_dostep(const Host *h, int rounds, const char *only, double only_h, Err *err) {
    enum { N_CASES = N_FEEDS * N_BENCH_H };
    int order[N_CASES];
    printf("round,feed,h,steps,seconds\n");
    for (int r = 0; r <= rounds; r++) {
        for (int i = 0; i < N_CASES; i++) order[i] = i;
        uint64_t state = 0x9e3779b97f4a7c15u * (uint64_t)(r + 1);
        for (int i = N_CASES - 1; i > 0; i--) { /* Fisher-Yates with a 64-bit LCG (Knuth's MMIX) */
            state = state * 6364136223846793005u + 1442695040888963407u;
            int j = (int)((state >> 33) % (uint64_t)(i + 1));
            int tmp = order[i];
            order[i] = order[j], order[j] = tmp;
        }
        for (int i = 0; i < N_CASES; i++) {
            int feed = order[i] / (int)N_BENCH_H;
            double hc = BENCH_H[order[i] % (int)N_BENCH_H];
            if (only && strcmp(only, FEEDS[feed])) continue;
            if (only_h > 0.0 && hc != only_h) continue;
            if (feed >= FEED_EXACT_BDF && hc != EXACT_H) continue;
            double seconds = 0.0;
            int steps = 0;
            if (bench_case(h, feed, hc, &seconds, &steps, err)) return -1;
            printf("%d,%s,%g,%d,%.9f\n", r, FEEDS[feed], hc, steps, seconds);
        }
        fflush(stdout);
    }
    return 0;
}

/* ----- main --------------------------------------------------------------------------------- */

static int usage(void) {
    fprintf(stderr, "usage: host UNZIPDIR [--fmi3] [--cycles N] [--threads K] [-o TRAJ.csv] "
                    "[--me-out TRAJ.csv] [--so LIB] "
                    "[--save-state S STATE.bin] [--resume STATE.bin] "
                    "[--no-dlclose | --reloads R]\n"
                    "       host UNZIPDIR --bench-dostep ROUNDS [--feed FEED] [--h H]\n");
    return 2;
}

/* The FMU's resources folder as a file URI (file:///C:/... on Windows, file:///tmp/... here);
 * FMI 3.0 takes it as a path, with a trailing separator. */
static void resources_uri(char *dst, size_t cap, const char *unzipdir, int fmi3) {
    if (fmi3) {
        snprintf(dst, cap, "%s/resources/", unzipdir);
        return;
    }
    const char *slash = unzipdir[0] == '/' ? "" : "/";
    snprintf(dst, cap, "file://%s%s/resources", slash, unzipdir);
    for (char *p = dst; *p; p++)
        if (*p == '\\') *p = '/';
}

int main(int argc, char **argv) {
    const char *unzipdir = NULL, *out_csv = NULL, *me_csv = NULL, *so = NULL;
    int cycles = 1000, threads = 8, reloads = 0, do_dlclose = 1, bench_rounds = -1, fmi3 = 0;
    const char *bench_only = NULL;
    double bench_h = 0.0;
    StateIO io = {.save_step = -1};
    platform_init();
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--cycles") && a + 1 < argc)
            cycles = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--threads") && a + 1 < argc)
            threads = atoi(argv[++a]);
        else if (!strcmp(argv[a], "-o") && a + 1 < argc)
            out_csv = argv[++a];
        else if (!strcmp(argv[a], "--me-out") && a + 1 < argc)
            me_csv = argv[++a];
        else if (!strcmp(argv[a], "--reloads") && a + 1 < argc)
            reloads = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--so") && a + 1 < argc)
            so = argv[++a];
        else if (!strcmp(argv[a], "--save-state") && a + 2 < argc) {
            io.save_step = atoi(argv[++a]);
            io.save_file = argv[++a];
        } else if (!strcmp(argv[a], "--resume") && a + 1 < argc)
            io.resume_file = argv[++a];
        else if (!strcmp(argv[a], "--bench-dostep") && a + 1 < argc)
            bench_rounds = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--feed") && a + 1 < argc)
            bench_only = argv[++a];
        else if (!strcmp(argv[a], "--h") && a + 1 < argc)
            bench_h = atof(argv[++a]);
        else if (!strcmp(argv[a], "--no-dlclose"))
            do_dlclose = 0;
        else if (!strcmp(argv[a], "--fmi3"))
            fmi3 = 1;
        else if (argv[a][0] != '-' && !unzipdir)
            unzipdir = argv[a];
        else
            return usage();
    }
    if (!unzipdir || cycles < 0 || threads < 0 || threads > 256 || reloads < 0 ||
        (reloads > 0 && !do_dlclose) ||
        (io.save_file && (io.save_step < 0 || io.save_step > N_STEPS)) ||
        (fmi3 && bench_rounds >= 0))
        return usage();
    g_fmi = fmi3 ? 3 : 2;

    Err err = {{0}};
    Model model;
    if (read_model(unzipdir, fmi3, &model, &err)) goto failed;
    char lib_path[4096], resources[4200];
    if (so)
        snprintf(lib_path, sizeof lib_path, "%s", so);
    else
        snprintf(lib_path, sizeof lib_path, "%s/%s", unzipdir, fmi3 ? LIB_DEFAULT3 : LIB_DEFAULT);
    resources_uri(resources, sizeof resources, unzipdir, fmi3);

    Lib lib = lib_open(lib_path);
    if (!lib) {
        fail(&err, "loading %s: %s", lib_path, lib_error());
        goto failed;
    }
    /* api: the functions checks 1-4 call (with --fmi3, FMI 3.0 through adapters); api2: FMI
     * 2.0's, for the mixing of versions in check 6 */
    Api api, api2;
    if (load_apis(lib, fmi3, &model, &api, &api2, &err)) goto failed;
    Host host = {&api, &model, resources};
    if (bench_rounds >= 0) return bench_dostep(&host, bench_rounds, bench_only, bench_h, &err) ? (fprintf(stderr, "host: FAILED: %s\n", err.msg), 1) : 0;
    if (fmi3)
        printf("host library=%s fmi=3.0 exports=%zu instantiationToken=%s\n", lib_path,
               N_EXPORTS3, model.guid);
    else
        printf("host library=%s guid=%s\n", lib_path, model.guid);

    if (check_scene(&host, out_csv, &io, &err)) goto failed;
    if (check_cycles(&host, cycles, &err)) goto failed;
    if (threads > 0 && check_threads(&host, threads, &err)) goto failed;
    if (check_exchange(&host, me_csv, &err)) goto failed;
    if (fmi3 && (check_intermediate(&g3.f, &model, resources, &err) ||
                 check_misuse(&api2, &g3.f, &model, resources, &err) ||
                 check_arrays(&g3.f, &model, resources, &err)))
        goto failed;

    long bad = atomic_load(&g_bad_log);
    if (bad) {
        fail(&err, "%ld log messages were unexpected or malformed (see above)", bad);
        goto failed;
    }
    /* Unloading is what hosts such as FMPy do when they are done; with valgrind this shows
     * whether the library leaves allocations behind that nothing can free any more. */
    if (do_dlclose) {
        if (unload(lib, lib_path, &err)) goto failed;
        /* Load, use and unload the library again: anything a load leaves behind then shows up
         * once per load in valgrind's leak summary. */
        for (int r = 0; r < reloads; r++) {
            if (!(lib = lib_open(lib_path))) {
                fail(&err, "reload %d: loading %s: %s", r, lib_path, lib_error());
                goto failed;
            }
            Api again, again2;
            Host h2 = {&again, &model, resources};
            if (load_apis(lib, fmi3, &model, &again, &again2, &err) || one_cycle(&h2, 4, &err) ||
                one_cycle(&h2, 5, &err) || unload(lib, lib_path, &err))
                goto failed;
        }
        if (reloads) printf("reloads n=%d\n", reloads);
    }
    printf("host result=PASS\n");
    return 0;

failed:
    fflush(stdout);
    fprintf(stderr, "host: FAILED: %s\n", err.msg);
    printf("host result=FAIL\n");
    return 1;
}
