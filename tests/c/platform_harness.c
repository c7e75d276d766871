/* Runs the FMU's library through both ABIs on any platform (Linux dlopen or
 * Windows LoadLibrary), for tests/python/test_platforms.py, which runs it
 * natively, under wine (the Windows DLL) and under qemu (the aarch64 library)
 * and compares the printed numbers.
 * FMI 2.0: the paper's stack under RECORD for 2 s in steps of 0.01 s, the
 * state saved at 1 s and restored, the second pass bit-identical to the first.
 * FMI 3.0: the same with early return allowed: every early-return time; with
 * RESOURCES (the folder holding default_record.csv, a native path), through
 * resourcePath and the relative recordFile "default_record.csv".
 * Usage: platform_harness LIBRARY GUID RECORD [RESOURCES]; prints "name value" lines
 * (%.17g), exit 0 on success. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "StackedLiveLoad.h"

#ifdef _WIN32
#include <windows.h>
#define OPEN(path) ((void *)LoadLibraryA(path))
#define SYM(lib, name) ((void *)GetProcAddress((HMODULE)(lib), name))
#else
#include <dlfcn.h>
#define OPEN(path) dlopen(path, RTLD_NOW | RTLD_LOCAL)
#define SYM(lib, name) dlsym(lib, name)
#endif

static void *lib;

static void *need(const char *name) {
    void *p = SYM(lib, name);
    if (!p) {
        fprintf(stderr, "missing %s\n", name);
        exit(2);
    }
    return p;
}
#define LOAD(f) __typeof__(&f) p_##f = (__typeof__(&f))need(#f)

static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                    fmi2String category, fmi2String message, ...) {
    (void)env;
    fprintf(stderr, "[%s %d %s] %s\n", name, status, category, message);
}

static void logger3(void *env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env;
    fprintf(stderr, "[fmi3 %d %s] %s\n", status, category, message);
}

#define CHECK(call)                                                  \
    if ((call) != 0) {                                               \
        fprintf(stderr, "failed: %s (line %d)\n", #call, __LINE__); \
        return 1;                                                    \
    }

/* up, slip[1], slip[2], peakUp */
static const unsigned OUTPUTS[4] = {200, 321, 322, 204};

static int fmi2(const char *guid, const char *record) {
    LOAD(fmi2Instantiate); LOAD(fmi2SetupExperiment); LOAD(fmi2EnterInitializationMode);
    LOAD(fmi2ExitInitializationMode); LOAD(fmi2SetString); LOAD(fmi2GetReal); LOAD(fmi2DoStep);
    LOAD(fmi2GetFMUstate); LOAD(fmi2SetFMUstate); LOAD(fmi2FreeFMUstate); LOAD(fmi2FreeInstance);
    fmi2CallbackFunctions cb = {logger2, NULL, NULL, NULL, NULL};
    fmi2Component c = p_fmi2Instantiate("harness", 1, guid, NULL, &cb, 0, 0);
    if (!c) return 1;
    const unsigned record_vr = 600;
    CHECK(p_fmi2SetString(c, &record_vr, 1, &record));
    CHECK(p_fmi2SetupExperiment(c, 0, 0.0, 0.0, 1, 2.0));
    CHECK(p_fmi2EnterInitializationMode(c));
    CHECK(p_fmi2ExitInitializationMode(c));
    double first[4], again[4], o[4];
    fmi2FMUstate saved = NULL;
    for (int pass = 0; pass < 2; pass++) {
        for (int k = pass ? 100 : 0; k < 200; k++) {
            CHECK(p_fmi2DoStep(c, k * 0.01, 0.01, 1));
            if (k == 99 && !pass) CHECK(p_fmi2GetFMUstate(c, &saved));
            CHECK(p_fmi2GetReal(c, OUTPUTS, 4, o));
            if (!pass && (k + 1) % 50 == 0)
                printf("fmi2 t=%.2f up %.17g slip1 %.17g slip2 %.17g peakUp %.17g\n",
                       (k + 1) * 0.01, o[0], o[1], o[2], o[3]);
        }
        memcpy(pass ? again : first, o, sizeof o);
        if (!pass) CHECK(p_fmi2SetFMUstate(c, saved));
    }
    if (memcmp(first, again, sizeof first) != 0) {
        fprintf(stderr, "the rollback is not bit-identical\n");
        return 1;
    }
    printf("fmi2 rollback bit-identical\n");
    CHECK(p_fmi2FreeFMUstate(c, &saved));
    p_fmi2FreeInstance(c);
    return 0;
}

static int fmi3(const char *guid, const char *record, const char *resources) {
    LOAD(fmi3InstantiateCoSimulation); LOAD(fmi3EnterInitializationMode);
    LOAD(fmi3ExitInitializationMode); LOAD(fmi3SetString); LOAD(fmi3GetFloat64);
    LOAD(fmi3DoStep); LOAD(fmi3FreeInstance);
    fmi3Instance c = p_fmi3InstantiateCoSimulation("harness", guid, resources, false, false,
                                                   false, true, NULL, 0, NULL, logger3, NULL);
    if (!c) return 1;
    if (resources) record = "default_record.csv";
    const unsigned record_vr = 600;
    CHECK(p_fmi3SetString(c, &record_vr, 1, &record, 1));
    CHECK(p_fmi3EnterInitializationMode(c, false, 0.0, 0.0, true, 2.0));
    CHECK(p_fmi3ExitInitializationMode(c));
    double t = 0.0, o[4];
    int early_returns = 0;
    for (int k = 1; k <= 200; k++) {
        double target = k * 0.01;
        for (;;) {
            bool event, terminate, early;
            double last;
            CHECK(p_fmi3DoStep(c, t, target - t, false, &event, &terminate, &early, &last));
            t = last;
            if (!early) break;
            early_returns++;
            printf("fmi3 early return %.17g\n", t);
        }
    }
    CHECK(p_fmi3GetFloat64(c, OUTPUTS, 4, o, 4));
    printf("fmi3 t=2.00 up %.17g slip1 %.17g slip2 %.17g peakUp %.17g early returns %d\n", o[0],
           o[1], o[2], o[3], early_returns);
    p_fmi3FreeInstance(c);
    return 0;
}

int main(int argc, char **argv) {
    if (argc != 4 && argc != 5) return 2;
    lib = OPEN(argv[1]);
    if (!lib) {
        fprintf(stderr, "cannot load %s\n", argv[1]);
        return 2;
    }
    if (fmi2(argv[2], argv[3]) != 0) return 1;
    if (fmi3(argv[2], argv[3], argc == 5 ? argv[4] : NULL) != 0) return 1;
    return 0;
}
