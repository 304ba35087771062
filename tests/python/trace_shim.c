/*
 * A call-tracing stand-in for binaries/linux64/BeamBody.so, used by the tests of third-party hosts
 * (tests/python/hosts/test_fmu_libcosim.py, test_fmu_ecos.py; built and packaged by
 * fmu_util.traced_fmu). It lets a test see every FMI call a host makes, with its arguments, when
 * the host offers no way to switch the FMU's logging on.
 *
 * The FMU is repacked with this library as BeamBody.so and the real one next to it as
 * REAL_LIBRARY (below). This library is linked against the real one (DT_NEEDED, RUNPATH $ORIGIN), so
 * the host's dlsym(handle, "fmi2DoStep") and every other lookup finds the real function through
 * the dependency: only fmi2Instantiate is defined here. It calls the real fmi2Instantiate with
 * loggingOn = fmi2True and a logger of its own, so the FMU's `logCalls` category traces every call
 * (its arguments, or its results for the get functions), and the messages go to the file named by
 * $BEAM_BODY_TRACE (appended; opened at this library's first fmi2Instantiate; stderr if unset), one
 * line each:
 *
 *     instanceName <TAB> status <TAB> category <TAB> message
 *
 * The first line of each instance, category `shim`, records the host's own loggingOn, visible and
 * resourceLocation. The host's logger is not called (its allocateMemory, freeMemory, stepFinished
 * and componentEnvironment are passed on unchanged). Nothing else differs from the real FMU; a host
 * that called fmi2SetDebugLogging could switch the trace off again (libcosim and Ecos do not).
 */
#define _GNU_SOURCE

#include <dlfcn.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* FMI 2.0 types, from the standard's fmi2TypesPlatform.h and fmi2FunctionTypes.h */
typedef void *fmi2Component;
typedef void *fmi2ComponentEnvironment;
typedef const char *fmi2String;
typedef int fmi2Boolean;
typedef int fmi2Status;
typedef int fmi2Type;

typedef void (*fmi2CallbackLogger)(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String,
                                   fmi2String, ...);
typedef struct {
    fmi2CallbackLogger logger;
    void *(*allocateMemory)(size_t, size_t);
    void (*freeMemory)(void *);
    void (*stepFinished)(fmi2ComponentEnvironment, fmi2Status);
    fmi2ComponentEnvironment componentEnvironment;
} fmi2CallbackFunctions;

typedef fmi2Component fmi2InstantiateTYPE(fmi2String, fmi2Type, fmi2String, fmi2String,
                                          const fmi2CallbackFunctions *, fmi2Boolean, fmi2Boolean);

static FILE *trace_file(void) {
    static FILE *out;
    if (!out) {
        const char *path = getenv("BEAM_BODY_TRACE");
        out = path ? fopen(path, "a") : NULL;
        if (!out) out = stderr;
    }
    return out;
}

static void trace_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                         fmi2String category, fmi2String format, ...) {
    (void)env;
    FILE *out = trace_file();
    va_list args;
    va_start(args, format);
    fprintf(out, "%s\t%d\t%s\t", name ? name : "", status, category ? category : "");
    vfprintf(out, format, args);
    fputc('\n', out);
    fflush(out);
    va_end(args);
}

/* The real library's file name, unique per traced copy (fmu_util.traced_fmu passes it): the dynamic
   loader resolves a DT_NEEDED name against the libraries already loaded, so two traced copies that
   named their real library alike would share the first one loaded. */
#ifndef REAL_LIBRARY
#define REAL_LIBRARY "BeamBody_real.so"
#endif

/* The real library's fmi2Instantiate: REAL_LIBRARY in this library's directory, loaded with it
   (DT_NEEDED). The reference dlopen takes is dropped again, so that the real library is unloaded
   with this one. */
static fmi2InstantiateTYPE *real_instantiate(void) {
    Dl_info info;
    if (!dladdr((void *)&real_instantiate, &info) || !info.dli_fname) return NULL;
    char path[4096];
    const char *slash = strrchr(info.dli_fname, '/');
    size_t dir = slash ? (size_t)(slash - info.dli_fname + 1) : 0;
    if (dir + sizeof REAL_LIBRARY > sizeof path) return NULL;
    memcpy(path, info.dli_fname, dir);
    strcpy(path + dir, REAL_LIBRARY);
    void *lib = dlopen(path, RTLD_NOW | RTLD_NOLOAD);
    if (!lib) return NULL;
    fmi2InstantiateTYPE *f = (fmi2InstantiateTYPE *)dlsym(lib, "fmi2Instantiate");
    dlclose(lib);
    return f;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String guid,
                              fmi2String resourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    fmi2InstantiateTYPE *real = real_instantiate();
    FILE *out = trace_file();
    fprintf(out, "%s\t0\tshim\tfmi2Instantiate: loggingOn = %d, visible = %d, resourceLocation = %s\n",
            instanceName ? instanceName : "", loggingOn, visible,
            resourceLocation ? resourceLocation : "(null)");
    fflush(out);
    if (!real || !functions) {
        fprintf(out, "%s\t3\tshim\tfmi2Instantiate: %s\n", instanceName ? instanceName : "",
                real ? "no callback functions" : "the real library " REAL_LIBRARY " is not loaded");
        fflush(out);
        return NULL;
    }
    /* The FMU keeps this pointer for the instance's lifetime: never freed (a few bytes per
       instance, in a test process). */
    fmi2CallbackFunctions *ours = malloc(sizeof *ours);
    if (!ours) return NULL;
    *ours = *functions;
    ours->logger = trace_logger;
    return real(instanceName, fmuType, guid, resourceLocation, ours, visible, 1);
}
