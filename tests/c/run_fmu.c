/* Loads the FMU's shared library with dlopen, checks that all 34 FMI 2.0
 * Co-Simulation functions are there, and runs the default scene under a held
 * ground acceleration of 0.2 m/s2 for 1 s through the C ABI.
 * Oracle: the blocks stay stuck (0.2 m/s2 is below mu g for both interfaces
 * even with the step response's overshoot), so the structure is a rigid SDOF
 * of mass 1.5 mp: u(t) = -(a/w^2) (1 - e^{-z w t} (cos wd t + z/sqrt(1-z^2) sin wd t)).
 * Usage: run_fmu LIBRARY GUID; exit 0 on success. */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include "StackedLiveLoad.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    va_list args;
    (void)env;
    printf("[%s %d %s] ", name, status, category);
    va_start(args, message);
    vprintf(message, args);
    va_end(args);
    printf("\n");
}

static const char *functions[] = {
    "fmi2GetTypesPlatform", "fmi2GetVersion", "fmi2SetDebugLogging", "fmi2Instantiate",
    "fmi2FreeInstance", "fmi2SetupExperiment", "fmi2EnterInitializationMode",
    "fmi2ExitInitializationMode", "fmi2Terminate", "fmi2Reset", "fmi2GetReal", "fmi2GetInteger",
    "fmi2GetBoolean", "fmi2GetString", "fmi2SetReal", "fmi2SetInteger", "fmi2SetBoolean",
    "fmi2SetString", "fmi2GetFMUstate", "fmi2SetFMUstate", "fmi2FreeFMUstate",
    "fmi2SerializedFMUstateSize", "fmi2SerializeFMUstate", "fmi2DeSerializeFMUstate",
    "fmi2GetDirectionalDerivative", "fmi2SetRealInputDerivatives", "fmi2GetRealOutputDerivatives",
    "fmi2DoStep", "fmi2CancelStep", "fmi2GetStatus", "fmi2GetRealStatus", "fmi2GetIntegerStatus",
    "fmi2GetBooleanStatus", "fmi2GetStringStatus"};

#define LOAD(f)                                                   \
    __typeof__(&f) p_##f = (__typeof__(&f))dlsym(lib, #f);        \
    if (!p_##f) {                                                 \
        fprintf(stderr, "missing %s\n", #f);                      \
        return 2;                                                 \
    }

int main(int argc, char **argv) {
    if (argc != 3) return 2;
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "%s\n", dlerror());
        return 2;
    }
    for (size_t i = 0; i < sizeof functions / sizeof *functions; i++) {
        if (!dlsym(lib, functions[i])) {
            fprintf(stderr, "missing %s\n", functions[i]);
            return 2;
        }
    }
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2SetReal) LOAD(fmi2GetReal) LOAD(fmi2DoStep)
    LOAD(fmi2Terminate) LOAD(fmi2FreeInstance) LOAD(fmi2GetVersion)

    if (strcmp(p_fmi2GetVersion(), "2.0") != 0) return 3;
    fmi2CallbackFunctions cb = {logger, NULL, NULL, NULL, NULL};
    fmi2Component c = p_fmi2Instantiate("c-test", 1, argv[2], NULL, &cb, 0, 0);
    if (!c) return 4;
    if (p_fmi2SetupExperiment(c, 0, 0.0, 0.0, 1, 1.0) != 0) return 5;
    if (p_fmi2EnterInitializationMode(c) != 0) return 5;
    if (p_fmi2ExitInitializationMode(c) != 0) return 5;
    const fmi2ValueReference ag = 100, up = 200, stuck_vr[2] = {501, 502};
    (void)stuck_vr;
    const double a = 0.2;
    if (p_fmi2SetReal(c, &ag, 1, &a) != 0) return 6;
    double t = 0.0, h = 0.005;
    for (int i = 0; i < 200; i++, t += h)
        if (p_fmi2DoStep(c, t, h, 1) != 0) return 7;
    double u;
    if (p_fmi2GetReal(c, &up, 1, &u) != 0) return 8;

    const double pi = 3.14159265358979323846, mass_ratio = 1.5;
    double w = 2.0 * pi / 0.5 / sqrt(mass_ratio), z = 0.05 / sqrt(mass_ratio);
    double wd = w * sqrt(1.0 - z * z);
    double exact = -(a / (w * w)) * (1.0 - exp(-z * w * 1.0) * (cos(wd) + z / sqrt(1.0 - z * z) * sin(wd)));
    double err = fabs(u - exact) / fabs(exact);
    printf("up(1 s) = %.12e, exact %.12e, relative error %.2e\n", u, exact, err);
    p_fmi2Terminate(c);
    p_fmi2FreeInstance(c);
    dlclose(lib);
    return err < 1e-8 ? 0 : 1;
}
