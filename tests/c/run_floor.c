/* Loads the FMU's shared library with dlopen and runs StackOnFloor through
 * the FMI 2.0 C ABI, as an importer of StackOnFloor.fmu does: instantiated
 * with the StackOnFloor GUID (argv[2]); a GUID of no model is refused.
 * Scene: 3 blocks of 400, 150 and 75 kg (mus 0.3 0.2 0.1, muk 0.25 0.2
 * 0.08) on a floor whose acceleration the program sets at every 10 ms step
 * with a slope, from integer arithmetic only (no libm): the Rust side
 * (tests/c_abi.rs) runs the engine on the same inputs and compares every
 * printed number bit for bit. Prints, per step, floorForce attachedMass
 * slidingForce abAbs[1] F[1] ub[3] and d floorForce / d ag, as %.17g.
 * Usage: run_floor LIBRARY GUID; exit 0 on success. */
#include <dlfcn.h>
#include <stdio.h>
#include <string.h>
#include "StackedLiveLoad.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)env;
    (void)name;
    (void)message;
    /* The message is the argument of a "%s" format. */
    fprintf(stderr, "[%d %s] logged\n", status, category);
}

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
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2SetReal) LOAD(fmi2SetInteger) LOAD(fmi2GetReal)
    LOAD(fmi2DoStep) LOAD(fmi2Terminate) LOAD(fmi2FreeInstance)
    LOAD(fmi2SetRealInputDerivatives) LOAD(fmi2GetDirectionalDerivative)

    fmi2CallbackFunctions cb = {logger, NULL, NULL, NULL, NULL};
    if (p_fmi2Instantiate("wrong", 1, "{00000000-0000-0000-0000-000000000000}", NULL, &cb, 0, 0))
        return 3;
    fmi2Component c = p_fmi2Instantiate("floor", 1, argv[2], NULL, &cb, 0, 0);
    if (!c) return 4;
    if (p_fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) != 0) return 5;
    if (p_fmi2EnterInitializationMode(c) != 0) return 5;
    const fmi2ValueReference n_blocks = 400;
    const int three = 3;
    if (p_fmi2SetInteger(c, &n_blocks, 1, &three) != 0) return 5;
    /* m[j] 41.., mus[j] 21.., muk[j] 31.. */
    const fmi2ValueReference params[9] = {41, 42, 43, 21, 22, 23, 31, 32, 33};
    const double values[9] = {400.0, 150.0, 75.0, 0.3, 0.2, 0.1, 0.25, 0.2, 0.08};
    if (p_fmi2SetReal(c, params, 9, values) != 0) return 5;
    /* m[1] = -1 kg is refused, and changes nothing. */
    const double negative = -1.0;
    if (p_fmi2SetReal(c, params, 1, &negative) != 3) return 5;
    if (p_fmi2ExitInitializationMode(c) != 0) return 5;

    const fmi2ValueReference ag = 100, mobility = 102;
    const fmi2ValueReference out[6] = {212, 213, 214, 331, 341, 303};
    const int order = 1;
    double t = 0.0, h = 0.01;
    for (int k = 0; k < 300; k++, t += h) {
        double a = 0.5 * (double)((k * 37) % 17 - 8);
        double slope = 10.0 * (double)((k * 13) % 11 - 5);
        double mb = k < 150 ? 0.0 : 2e-3;
        if (p_fmi2SetReal(c, &ag, 1, &a) != 0) return 6;
        if (p_fmi2SetReal(c, &mobility, 1, &mb) != 0) return 6;
        if (p_fmi2SetRealInputDerivatives(c, &ag, 1, &order, &slope) != 0) return 6;
        if (p_fmi2DoStep(c, t, h, 1) != 0) return 7;
        double y[6], seed = 1.0, dd;
        if (p_fmi2GetReal(c, out, 6, y) != 0) return 8;
        if (p_fmi2GetDirectionalDerivative(c, out, 1, &ag, 1, &seed, &dd) != 0) return 9;
        if (dd != -y[1]) return 10; /* d floorForce / d ag = -attachedMass */
        printf("%.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", y[0], y[1], y[2], y[3], y[4],
               y[5], dd);
    }
    p_fmi2Terminate(c);
    p_fmi2FreeInstance(c);
    dlclose(lib);
    return 0;
}
