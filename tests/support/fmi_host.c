/* A minimal FMI 2.0 co-simulation host in C, compiled by tests/integration/orchestrator/builder/fmi_binary/conftest.py
 * (fixture c_host; test_fmi_binary_c_host.py also builds it with -fsanitize=address,undefined).
 *
 * It loads each FMU's linux64 binary with dlopen (RTLD_NOW | RTLD_LOCAL, as C tools do), runs the
 * full call sequence (instantiate, setup, enter/exit initialisation, a doStep loop with set/get,
 * terminate, free), dlcloses the binaries unless --keep-loaded, and returns from main. All FMUs
 * of a plan live in this one process at the same time, stepped in turn.
 *
 * Plan (whitespace separated) on stdin:
 *   <n_fmus> <n_steps>
 *   per FMU: <binary> <guid> <resource uri> <instance name> <step size>
 *            <n_real_in> vr... <n_int_in> vr... <n_bool_in> vr...
 *            <n_real_out> vr... <n_int_out> vr... <n_bool_out> vr...
 *   per step, per FMU: real inputs, integer inputs, boolean inputs (0/1)
 * Output: per step, per FMU, one line "<step> <fmu index> <outputs...>" with %.17g reals.
 */
#include <dlfcn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MAX_PORTS 64

typedef struct {
    void *library;
    fmi2Component component;
    double step;
    size_t n[6];
    fmi2ValueReference vr[6][MAX_PORTS];
    fmi2SetRealTYPE *setReal;
    fmi2SetIntegerTYPE *setInteger;
    fmi2SetBooleanTYPE *setBoolean;
    fmi2GetRealTYPE *getReal;
    fmi2GetIntegerTYPE *getInteger;
    fmi2GetBooleanTYPE *getBoolean;
    fmi2DoStepTYPE *doStep;
} Fmu;

static void logger(fmi2ComponentEnvironment environment, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)environment;
    va_list args;
    va_start(args, message);
    fprintf(stderr, "log %s status=%d %s: ", instance, (int)status, category);
    vfprintf(stderr, message, args);
    fputc('\n', stderr);
    va_end(args);
}

static void *symbol(Fmu *fmu, const char *name) {
    void *address = dlsym(fmu->library, name);
    if (address == NULL) {
        fprintf(stderr, "missing %s\n", name);
        exit(3);
    }
    return address;
}

#define CHECK(call, what)                                                                      \
    do {                                                                                       \
        fmi2Status status_ = (call);                                                           \
        if (status_ > fmi2Warning) {                                                           \
            fprintf(stderr, "%s failed with status %d\n", what, (int)status_);                 \
            return 4;                                                                          \
        }                                                                                      \
    } while (0)

int main(int argc, char **argv) {
    int keep_loaded = argc > 1 && strcmp(argv[1], "--keep-loaded") == 0;
    size_t n_fmus, n_steps;
    if (scanf("%zu %zu", &n_fmus, &n_steps) != 2 || n_fmus == 0 || n_fmus > 16) return 2;
    Fmu *fmus = calloc(n_fmus, sizeof *fmus);
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    for (size_t f = 0; f < n_fmus; f++) {
        Fmu *fmu = &fmus[f];
        char binary[4096], guid[256], uri[4096], name[256];
        if (scanf("%4095s %255s %4095s %255s %lf", binary, guid, uri, name, &fmu->step) != 5)
            return 2;
        for (int group = 0; group < 6; group++) {
            if (scanf("%zu", &fmu->n[group]) != 1 || fmu->n[group] > MAX_PORTS) return 2;
            for (size_t i = 0; i < fmu->n[group]; i++)
                if (scanf("%u", &fmu->vr[group][i]) != 1) return 2;
        }
        fmu->library = dlopen(binary, RTLD_NOW | RTLD_LOCAL);
        if (fmu->library == NULL) {
            fprintf(stderr, "dlopen failed: %s\n", dlerror());
            return 3;
        }
        fmi2InstantiateTYPE *instantiate = symbol(fmu, "fmi2Instantiate");
        fmu->setReal = symbol(fmu, "fmi2SetReal");
        fmu->setInteger = symbol(fmu, "fmi2SetInteger");
        fmu->setBoolean = symbol(fmu, "fmi2SetBoolean");
        fmu->getReal = symbol(fmu, "fmi2GetReal");
        fmu->getInteger = symbol(fmu, "fmi2GetInteger");
        fmu->getBoolean = symbol(fmu, "fmi2GetBoolean");
        fmu->doStep = symbol(fmu, "fmi2DoStep");
        fmu->component = instantiate(name, fmi2CoSimulation, guid, uri, &callbacks, fmi2False,
                                     fmi2False);
        if (fmu->component == NULL) {
            fprintf(stderr, "fmi2Instantiate of %s returned NULL\n", name);
            return 4;
        }
        fmi2SetupExperimentTYPE *setup = symbol(fmu, "fmi2SetupExperiment");
        fmi2EnterInitializationModeTYPE *enter = symbol(fmu, "fmi2EnterInitializationMode");
        fmi2ExitInitializationModeTYPE *leave = symbol(fmu, "fmi2ExitInitializationMode");
        CHECK(setup(fmu->component, fmi2False, 0.0, 0.0, fmi2False, 0.0), "fmi2SetupExperiment");
        CHECK(enter(fmu->component), "fmi2EnterInitializationMode");
        CHECK(leave(fmu->component), "fmi2ExitInitializationMode");
    }
    for (size_t k = 0; k < n_steps; k++) {
        for (size_t f = 0; f < n_fmus; f++) {
            Fmu *fmu = &fmus[f];
            fmi2Real reals[MAX_PORTS];
            fmi2Integer integers[MAX_PORTS];
            fmi2Boolean booleans[MAX_PORTS];
            for (size_t i = 0; i < fmu->n[0]; i++)
                if (scanf("%lf", &reals[i]) != 1) return 2;
            for (size_t i = 0; i < fmu->n[1]; i++)
                if (scanf("%d", &integers[i]) != 1) return 2;
            for (size_t i = 0; i < fmu->n[2]; i++)
                if (scanf("%d", &booleans[i]) != 1) return 2;
            if (fmu->n[0]) CHECK(fmu->setReal(fmu->component, fmu->vr[0], fmu->n[0], reals), "fmi2SetReal");
            if (fmu->n[1]) CHECK(fmu->setInteger(fmu->component, fmu->vr[1], fmu->n[1], integers), "fmi2SetInteger");
            if (fmu->n[2]) CHECK(fmu->setBoolean(fmu->component, fmu->vr[2], fmu->n[2], booleans), "fmi2SetBoolean");
            /* time from the integer step count, as the master does */
            CHECK(fmu->doStep(fmu->component, (double)k * fmu->step, fmu->step, fmi2True), "fmi2DoStep");
            if (fmu->n[3]) CHECK(fmu->getReal(fmu->component, fmu->vr[3], fmu->n[3], reals), "fmi2GetReal");
            if (fmu->n[4]) CHECK(fmu->getInteger(fmu->component, fmu->vr[4], fmu->n[4], integers), "fmi2GetInteger");
            if (fmu->n[5]) CHECK(fmu->getBoolean(fmu->component, fmu->vr[5], fmu->n[5], booleans), "fmi2GetBoolean");
            printf("%zu %zu", k, f);
            for (size_t i = 0; i < fmu->n[3]; i++) printf(" %.17g", reals[i]);
            for (size_t i = 0; i < fmu->n[4]; i++) printf(" %d", integers[i]);
            for (size_t i = 0; i < fmu->n[5]; i++) printf(" %d", booleans[i]);
            printf("\n");
        }
    }
    for (size_t f = 0; f < n_fmus; f++) {
        Fmu *fmu = &fmus[f];
        fmi2TerminateTYPE *terminate = symbol(fmu, "fmi2Terminate");
        fmi2FreeInstanceTYPE *free_instance = symbol(fmu, "fmi2FreeInstance");
        CHECK(terminate(fmu->component), "fmi2Terminate");
        free_instance(fmu->component);
    }
    for (size_t f = 0; f < n_fmus && !keep_loaded; f++) {
        if (dlclose(fmus[f].library) != 0) {
            fprintf(stderr, "dlclose failed: %s\n", dlerror());
            return 5;
        }
    }
    free(fmus);
    fflush(stdout);
    return 0;
}
