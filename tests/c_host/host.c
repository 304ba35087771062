/*
 * A minimal FMI 2.0 co-simulation host for the BeamBody FMU, used as a test fixture by
 * tests/python/test_c_host.py (which compiles it with the system's cc and runs it natively and
 * under valgrind). It loads binaries/linux64/BeamBody.so of an unzipped FMU with dlopen/dlsym,
 * as a real host would, and runs three checks:
 *
 *   1. scene:   the paper's scene (default parameters, phi_source = law, t = 0 .. 10.2 s,
 *               communication step 0.01 s, tolerance undefined = the FMU's default) recording
 *               v1, theta1, u2 at every communication point; all must be finite. A summary goes
 *               to stdout and, with -o, the whole trajectory as CSV (%.17g: round-trips exactly).
 *   2. cycles:  N fmi2Instantiate/fmi2FreeInstance cycles, most also doing a part of the life
 *               cycle (set-up, a few steps, FMU states and their serialization, reset, calls
 *               out of sequence, rejected instantiations), every status checked.
 *   3. threads: K instances (each with its own phi_end and EI) created, stepped over the paper's
 *               scene and freed in K concurrent pthreads; the trajectories must be bit-identical
 *               to the same K configurations run one after another in the main thread.
 *
 * usage: host UNZIPDIR [--cycles N] [--threads K] [-o TRAJ.csv] [--so LIB.so]
 *                     [--no-dlclose | --reloads R]
 * --so loads another build of the library (with the unzipped FMU's modelDescription.xml);
 * --no-dlclose keeps the library loaded at exit; --reloads R then loads, uses (one plain and one
 * FMU-state cycle) and unloads it R more times.
 * Exit code: 0 when every check passed, 1 on a failure (with a message on stderr), 2 on bad usage.
 *
 * The FMI 2.0 types are written here from the standard's headers (fmi2TypesPlatform.h,
 * fmi2FunctionTypes.h) so that the fixture needs nothing beyond libc, pthread and dlfcn.
 */
#define _POSIX_C_SOURCE 200809L

#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

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
typedef fmi2Status fmi2GetRealStatusTYPE(fmi2Component, const fmi2StatusKind, fmi2Real *);
typedef fmi2Status fmi2GetBooleanStatusTYPE(fmi2Component, const fmi2StatusKind, fmi2Boolean *);

/* Every function a CS FMU must export (fmi-notes: 25 common + 9 CS); all are looked up so that
 * a missing export fails here, as it would in FMPy. */
static const char *const ALL_EXPORTS[] = {
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate",
    "fmi2FreeInstance", "fmi2SetupExperiment", "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset", "fmi2GetReal", "fmi2GetInteger",
    "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean",
    "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative", "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives",
    "fmi2DoStep", "fmi2CancelStep", "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus", "fmi2GetStringStatus",
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
    fmi2GetRealStatusTYPE *GetRealStatus;
    fmi2GetBooleanStatusTYPE *GetBooleanStatus;
} Api;

/* ----- the model's interface, read from modelDescription.xml ------------------------------- */

typedef struct {
    char guid[128];
    fmi2ValueReference ei, phi_end, phi_source, v1, theta1, u2;
} Model;

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

static int fail(Err *e, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static int fail(Err *e, const char *fmt, ...) {
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->msg, sizeof e->msg, fmt, ap);
    va_end(ap);
    return -1;
}

static const char *status_name(int s) {
    static const char *const names[] = {"fmi2OK",    "fmi2Warning", "fmi2Discard",
                                        "fmi2Error", "fmi2Fatal",   "fmi2Pending"};
    return s >= 0 && s <= 5 ? names[s] : "(not an fmi2Status)";
}

/* Calls `call`, which must return fmi2OK; otherwise records the call's text, line, status and
 * the instance's last log message, and jumps to the function's `out` label. Expects `who` (a
 * name for the message), `lc` (the instance's LogCtx) and `err` in scope. */
#define OK(call)                                                                               \
    do {                                                                                       \
        fmi2Status got_ = (call);                                                              \
        if (got_ != fmi2OK) {                                                                  \
            fail(err, "%s: line %d: %s returned %s (last message: `%s`)", who, __LINE__, #call, \
                 status_name(got_), lc->last);                                                 \
            goto out;                                                                          \
        }                                                                                      \
    } while (0)

/* A call out of sequence or with a bad argument: it must return fmi2Error and log exactly one
 * error (which the logger then does not count as unexpected). */
#define REFUSED(call)                                                                          \
    do {                                                                                       \
        long before_ = lc->count[fmi2Error];                                                   \
        lc->expect_errors = 1;                                                                 \
        fmi2Status got_ = (call);                                                              \
        lc->expect_errors = 0;                                                                 \
        if (got_ != fmi2Error || lc->count[fmi2Error] != before_ + 1) {                        \
            fail(err, "%s: line %d: %s returned %s with %ld error messages, expected "         \
                      "fmi2Error and one message",                                             \
                 who, __LINE__, #call, status_name(got_), lc->count[fmi2Error] - before_);     \
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

static void logger(fmi2ComponentEnvironment env, fmi2String instanceName, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    char text[1024];
    va_list ap;
    va_start(ap, message);
    /* printf-like, as the standard requires: the FMU passes "%s" and the text. */
    vsnprintf(text, sizeof text, message ? message : "(null format)", ap);
    va_end(ap);
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
    if (!instanceName || strcmp(instanceName, ctx->name) != 0 || !known) {
        atomic_fetch_add(&g_bad_log, 1);
        fprintf(stderr, "logger: [%s] instanceName `%s` (expected `%s`), category `%s`: %s\n",
                status_name(status), instanceName ? instanceName : "(null)", ctx->name,
                category ? category : "(null)", text);
    }
    if ((int)status >= 0 && (int)status <= 5) ctx->count[status]++;
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

static void ctx_init(LogCtx *ctx, const char *name) {
    memset(ctx, 0, sizeof *ctx);
    ctx->magic = CTX_MAGIC;
    ctx->quiet = 1;
    snprintf(ctx->name, sizeof ctx->name, "%s", name);
}

/* ----- loading ------------------------------------------------------------------------------ */

static char *read_file(const char *path) {
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
    fclose(f);
    if (buf) buf[n] = '\0';
    return buf;
}

/* The value reference of the ScalarVariable called `name` (xtask writes `name` then
 * `valueReference`, in that order, on one line). */
static int find_vr(const char *xml, const char *name, fmi2ValueReference *vr, Err *err) {
    char key[96];
    snprintf(key, sizeof key, "<ScalarVariable name=\"%s\" valueReference=\"", name);
    const char *p = strstr(xml, key);
    if (!p) return fail(err, "modelDescription.xml: no ScalarVariable named `%s`", name);
    *vr = (fmi2ValueReference)strtoul(p + strlen(key), NULL, 10);
    return 0;
}

static int read_model(const char *unzipdir, Model *m, Err *err) {
    char path[4096];
    snprintf(path, sizeof path, "%s/modelDescription.xml", unzipdir);
    char *xml = read_file(path);
    if (!xml) return fail(err, "cannot read %s", path);
    int rc = -1;
    const char *g = strstr(xml, " guid=\"");
    const char *end = g ? strchr(g + 7, '"') : NULL;
    if (!g || !end || (size_t)(end - g - 7) >= sizeof m->guid) {
        fail(err, "%s: no guid attribute", path);
        goto out;
    }
    memcpy(m->guid, g + 7, (size_t)(end - g - 7));
    m->guid[end - g - 7] = '\0';
    if (find_vr(xml, "EI", &m->ei, err) || find_vr(xml, "phi_end", &m->phi_end, err) ||
        find_vr(xml, "phi_source", &m->phi_source, err) || find_vr(xml, "v1", &m->v1, err) ||
        find_vr(xml, "theta1", &m->theta1, err) || find_vr(xml, "u2", &m->u2, err))
        goto out;
    rc = 0;
out:
    free(xml);
    return rc;
}

static int load_api(void *lib, Api *api, Err *err) {
    for (size_t k = 0; k < N_EXPORTS; k++)
        if (!dlsym(lib, ALL_EXPORTS[k]))
            return fail(err, "the library does not export %s (%s)", ALL_EXPORTS[k], dlerror());
    /* dlsym returns void *, which POSIX (not ISO C) allows to convert to a function pointer. */
#define SYM(field, name) api->field = (__typeof__(api->field))dlsym(lib, name)
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
    SYM(GetRealStatus, "fmi2GetRealStatus");
    SYM(GetBooleanStatus, "fmi2GetBooleanStatus");
#undef SYM
    if (strcmp(api->GetVersion(), "2.0") != 0)
        return fail(err, "fmi2GetVersion() = `%s`, expected `2.0`", api->GetVersion());
    if (strcmp(api->GetTypesPlatform(), "default") != 0)
        return fail(err, "fmi2GetTypesPlatform() = `%s`, expected `default`",
                    api->GetTypesPlatform());
    return 0;
}

/* Everything an instance needs from the host. */
typedef struct {
    const Api *api;
    const Model *model;
    const char *resources; /* file URI of the FMU's resources folder */
} Host;

/* The callbacks: the memory functions are given although canNotUseMemoryManagementFunctions is
 * true (a host may always pass them; the FMU must not call them). */
static fmi2Component instantiate(const Host *h, LogCtx *ctx, fmi2CallbackFunctions *cb,
                                 const char *guid, fmi2Type type, fmi2Boolean logging_on) {
    /* the FMU keeps a pointer to the callbacks: they live as long as the instance */
    *cb = (fmi2CallbackFunctions){logger, calloc, free, NULL, ctx};
    return h->api->Instantiate(ctx->name, type, guid, h->resources, cb, fmi2False, logging_on);
}

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ----- 1 and 3: the paper's scene ----------------------------------------------------------- */

typedef struct {
    double phi_end, ei; /* NAN: the FMU's start value */
} SceneCfg;

#define N_POINTS (N_STEPS + 1)
typedef struct {
    double v1[N_POINTS], theta1[N_POINTS], u2[N_POINTS];
} Traj;

/* Instantiates, runs the scene with `cfg`, records the outputs at every communication point
 * (all must be finite), terminates and frees. */
static int run_scene(const Host *h, const char *name, const SceneCfg *cfg, Traj *out, Err *err) {
    const Api *f = h->api;
    const Model *m = h->model;
    const char *who = name;
    LogCtx ctx, *lc = &ctx;
    fmi2CallbackFunctions cb;
    ctx_init(&ctx, name);
    fmi2Component c = instantiate(h, &ctx, &cb, m->guid, fmi2CoSimulation, fmi2False);
    if (!c) return fail(err, "%s: fmi2Instantiate returned NULL (%s)", name, ctx.last);

    int rc = -1;
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
    for (int k = 0; k <= N_STEPS; k++) {
        if (k > 0) OK(f->DoStep(c, (k - 1) * H, H, fmi2True));
        OK(f->GetReal(c, out_vr, 3, y));
        if (!isfinite(y[0]) || !isfinite(y[1]) || !isfinite(y[2])) {
            fail(err, "%s: non-finite output at t = %g: v1 = %g, theta1 = %g, u2 = %g", name,
                 k * H, y[0], y[1], y[2]);
            goto out;
        }
        out->v1[k] = y[0];
        out->theta1[k] = y[1];
        out->u2[k] = y[2];
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

/* FNV-1a over the bytes of a trajectory: a compact fingerprint for the summary. */
static uint64_t fingerprint(const Traj *t) {
    const unsigned char *p = (const unsigned char *)t;
    uint64_t hash = 0xcbf29ce484222325u;
    for (size_t k = 0; k < sizeof *t; k++) hash = (hash ^ p[k]) * 0x100000001b3u;
    return hash;
}

static int check_scene(const Host *h, const char *out_csv, Err *err) {
    static Traj t; /* 24 kB: keep it off the stack */
    const SceneCfg paper = {NAN, NAN};
    double t0 = now();
    if (run_scene(h, "paper", &paper, &t, err)) return -1;
    double dt = now() - t0;

    double max_v1 = 0.0, max_theta1 = 0.0, max_u2 = 0.0;
    for (int k = 0; k < N_POINTS; k++) {
        max_v1 = fmax(max_v1, fabs(t.v1[k]));
        max_theta1 = fmax(max_theta1, fabs(t.theta1[k]));
        max_u2 = fmax(max_u2, fabs(t.u2[k]));
    }
    printf("scene points=%d h=%g t_end=%g seconds=%.3f\n", N_POINTS, H, T_END, dt);
    printf("scene_final v1=%.17g theta1=%.17g u2=%.17g\n", t.v1[N_STEPS], t.theta1[N_STEPS],
           t.u2[N_STEPS]);
    printf("scene_max_abs v1=%.17g theta1=%.17g u2=%.17g\n", max_v1, max_theta1, max_u2);
    printf("scene fingerprint=%016llx\n", (unsigned long long)fingerprint(&t));

    if (out_csv) {
        FILE *f = fopen(out_csv, "w");
        if (!f) return fail(err, "cannot write %s", out_csv);
        fprintf(f, "t,v1,theta1,u2\n");
        for (int k = 0; k < N_POINTS; k++)
            fprintf(f, "%.17g,%.17g,%.17g,%.17g\n", k * H, t.v1[k], t.theta1[k], t.u2[k]);
        if (fclose(f) != 0) return fail(err, "cannot write %s", out_csv);
    }
    return 0;
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
    case 2: /* rejected instantiations: wrong GUID, model exchange; each logs one error */
        for (int bad = 0; bad < 2; bad++) {
            ctx.expect_errors = 1;
            fmi2Component x =
                bad == 0 ? instantiate(h, &ctx, &cb, "{not-the-guid}", fmi2CoSimulation, fmi2False)
                         : instantiate(h, &ctx, &cb, m->guid, fmi2ModelExchange, fmi2False);
            ctx.expect_errors = 0;
            if (x) {
                f->FreeInstance(x);
                fail(err, "%s: fmi2Instantiate accepted a %s", name,
                     bad == 0 ? "wrong GUID" : "model-exchange type");
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
    pthread_barrier_t *start;
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

static void *thread_main(void *arg) {
    Job *job = arg;
    char name[64];
    snprintf(name, sizeof name, "thread%d", job->index);
    /* all threads start together, so that their instantiations and steps overlap */
    pthread_barrier_wait(job->start);
    job->rc = run_scene(job->host, name, &job->cfg, &job->traj, &job->err);
    return NULL;
}

static int check_threads(const Host *h, int n, Err *err) {
    Job *jobs = calloc((size_t)n, sizeof *jobs);
    Traj *ref = calloc((size_t)n, sizeof *ref);
    pthread_t *tid = calloc((size_t)n, sizeof *tid);
    int rc = -1, started = 0;
    pthread_barrier_t start;
    int barrier = 0;
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
        if (run_scene(h, name, &cfg, &ref[i], err)) goto out;
    }
    double t_seq = now() - t0;

    if (pthread_barrier_init(&start, NULL, (unsigned)n)) {
        fail(err, "pthread_barrier_init failed");
        goto out;
    }
    barrier = 1;
    t0 = now();
    for (int i = 0; i < n; i++) {
        jobs[i] = (Job){.host = h, .start = &start, .index = i, .cfg = thread_cfg(i), .rc = -1};
        if (pthread_create(&tid[i], NULL, thread_main, &jobs[i])) {
            fail(err, "pthread_create failed for thread %d", i);
            /* the started threads wait at the barrier for ever: exit without joining */
            goto out;
        }
        started++;
    }
    for (int i = 0; i < n; i++) pthread_join(tid[i], NULL);
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
               (unsigned long long)fingerprint(&jobs[i].traj));
    rc = 0;
out:
    if (started < n && started > 0) {
        fprintf(stderr, "host: %s\n", err->msg);
        exit(1);
    }
    if (barrier) pthread_barrier_destroy(&start);
    free(jobs);
    free(ref);
    free(tid);
    return rc;
}

/* dlclose, then reports whether the library really left the process: glibc keeps it mapped
 * (DF_1_NODELETE) when it registered thread-local destructors, for instance. */
static int unload(void *lib, const char *path, Err *err) {
    if (dlclose(lib)) return fail(err, "dlclose: %s", dlerror());
    void *still = dlopen(path, RTLD_NOW | RTLD_LOCAL | RTLD_NOLOAD);
    printf("dlclose unloaded=%d\n", still == NULL);
    if (still) dlclose(still);
    return 0;
}

/* ----- main --------------------------------------------------------------------------------- */

static int usage(void) {
    fprintf(stderr, "usage: host UNZIPDIR [--cycles N] [--threads K] [-o TRAJ.csv] [--so LIB.so] "
                    "[--no-dlclose | --reloads R]\n");
    return 2;
}

int main(int argc, char **argv) {
    const char *unzipdir = NULL, *out_csv = NULL, *so = NULL;
    int cycles = 1000, threads = 8, reloads = 0, do_dlclose = 1;
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--cycles") && a + 1 < argc)
            cycles = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--threads") && a + 1 < argc)
            threads = atoi(argv[++a]);
        else if (!strcmp(argv[a], "-o") && a + 1 < argc)
            out_csv = argv[++a];
        else if (!strcmp(argv[a], "--reloads") && a + 1 < argc)
            reloads = atoi(argv[++a]);
        else if (!strcmp(argv[a], "--so") && a + 1 < argc)
            so = argv[++a];
        else if (!strcmp(argv[a], "--no-dlclose"))
            do_dlclose = 0;
        else if (argv[a][0] != '-' && !unzipdir)
            unzipdir = argv[a];
        else
            return usage();
    }
    if (!unzipdir || cycles < 0 || threads < 1 || threads > 256 || reloads < 0 ||
        (reloads > 0 && !do_dlclose))
        return usage();

    Err err = {{0}};
    Model model;
    if (read_model(unzipdir, &model, &err)) goto failed;
    char lib_path[4096], resources[4200];
    if (so)
        snprintf(lib_path, sizeof lib_path, "%s", so);
    else
        snprintf(lib_path, sizeof lib_path, "%s/binaries/linux64/BeamBody.so", unzipdir);
    snprintf(resources, sizeof resources, "file://%s/resources", unzipdir);

    /* RTLD_LOCAL: the FMU's symbols must not leak into the global namespace (several FMUs
     * export the same fmi2* names); RTLD_NOW: a missing dependency fails here, not mid-run. */
    void *lib = dlopen(lib_path, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fail(&err, "dlopen(%s): %s", lib_path, dlerror());
        goto failed;
    }
    Api api;
    if (load_api(lib, &api, &err)) goto failed;
    Host host = {&api, &model, resources};
    printf("host library=%s guid=%s\n", lib_path, model.guid);

    if (check_scene(&host, out_csv, &err)) goto failed;
    if (check_cycles(&host, cycles, &err)) goto failed;
    if (check_threads(&host, threads, &err)) goto failed;

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
            if (!(lib = dlopen(lib_path, RTLD_NOW | RTLD_LOCAL))) {
                fail(&err, "reload %d: dlopen(%s): %s", r, lib_path, dlerror());
                goto failed;
            }
            Api again;
            Host h2 = {&again, &model, resources};
            if (load_api(lib, &again, &err) || one_cycle(&h2, 4, &err) ||
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
