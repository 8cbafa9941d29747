/* A minimal FMI 2.0 co-simulation host in C, compiled by tests/integration/orchestrator/builder/fmi_binary/conftest.py
 * (fixture c_host; the sanitizer tests also build it with -fsanitize=address,undefined).
 *
 * It loads each FMU's linux64 binary with dlopen (RTLD_NOW | RTLD_LOCAL, as C tools do), runs the
 * full call sequence (instantiate, setup, enter/exit initialisation, a doStep loop with set/get,
 * terminate, free), dlcloses the binaries unless --keep-loaded, and returns from main.
 *
 * Default: all FMUs of a plan live in this one process at the same time, stepped in turn by the
 * main thread. --threads: one thread per FMU of the plan, as multi-threaded hosts and FMU
 * containers do: each thread loads its binary, waits at a barrier so that every thread calls
 * fmi2Instantiate at the same moment, steps, and meets the others again at a barrier before
 * terminating and freeing, so that frees coincide too. The output is the same in both modes.
 * --timing (default mode): stderr gets the wall time of each FMU's fmi2Instantiate and of one
 * more instantiate after the run's free ("timing <fmu> first <s> later <s>"), for
 * benchmarks/fmi_call_cost.py.
 *
 * Plan (whitespace separated) on stdin:
 *   <n_fmus> <n_steps>
 *   per FMU: <binary> <guid> <resource uri> <instance name> <step size>
 *            <n_real_in> vr... <n_int_in> vr... <n_bool_in> vr...
 *            <n_real_out> vr... <n_int_out> vr... <n_bool_out> vr...
 *   per step, per FMU: real inputs, integer inputs, boolean inputs (0/1)
 * Output: per step, per FMU, one line "<step> <fmu index> <outputs...>" with %.17g reals.
 * Exit status: 0 done, 2 bad plan, 3 a binary or symbol missing, 4 an FMI call failed (the
 * call is named on stderr), 5 dlclose failed.
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <pthread.h>
#include <time.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

#define MAX_PORTS 64
#define MAX_FMUS 64

typedef struct {
    char binary[4096], guid[256], uri[4096], name[256];
    double instantiate_s; /* wall time of the first fmi2Instantiate (--timing) */
    void *library;
    fmi2Component component;
    double step;
    size_t n[6];
    fmi2ValueReference vr[6][MAX_PORTS];
    double *inputs;  /* n_steps x (n[0] + n[1] + n[2]) */
    double *outputs; /* n_steps x (n[3] + n[4] + n[5]) */
    int failed;
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *leave;
    fmi2SetRealTYPE *setReal;
    fmi2SetIntegerTYPE *setInteger;
    fmi2SetBooleanTYPE *setBoolean;
    fmi2GetRealTYPE *getReal;
    fmi2GetIntegerTYPE *getInteger;
    fmi2GetBooleanTYPE *getBoolean;
    fmi2DoStepTYPE *doStep;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_instance;
} Fmu;

static size_t n_steps;
static pthread_barrier_t instantiate_barrier, free_barrier;
static int threaded, timing;

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static void logger(fmi2ComponentEnvironment environment, fmi2String instance, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    (void)environment;
    va_list args;
    va_start(args, message);
    flockfile(stderr); /* one message, one line, whichever thread logs */
    fprintf(stderr, "log %s status=%d %s: ", instance, (int)status, category);
    vfprintf(stderr, message, args);
    fputc('\n', stderr);
    funlockfile(stderr);
    va_end(args);
}

static const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

static void *symbol(Fmu *fmu, const char *name) {
    void *address = dlsym(fmu->library, name);
    if (address == NULL) {
        fprintf(stderr, "missing %s\n", name);
        exit(3);
    }
    return address;
}

static int load(Fmu *fmu) {
    fmu->library = dlopen(fmu->binary, RTLD_NOW | RTLD_LOCAL);
    if (fmu->library == NULL) {
        fprintf(stderr, "dlopen failed: %s\n", dlerror());
        return 3;
    }
    fmu->instantiate = (fmi2InstantiateTYPE *)symbol(fmu, "fmi2Instantiate");
    fmu->setup = (fmi2SetupExperimentTYPE *)symbol(fmu, "fmi2SetupExperiment");
    fmu->enter = (fmi2EnterInitializationModeTYPE *)symbol(fmu, "fmi2EnterInitializationMode");
    fmu->leave = (fmi2ExitInitializationModeTYPE *)symbol(fmu, "fmi2ExitInitializationMode");
    fmu->setReal = (fmi2SetRealTYPE *)symbol(fmu, "fmi2SetReal");
    fmu->setInteger = (fmi2SetIntegerTYPE *)symbol(fmu, "fmi2SetInteger");
    fmu->setBoolean = (fmi2SetBooleanTYPE *)symbol(fmu, "fmi2SetBoolean");
    fmu->getReal = (fmi2GetRealTYPE *)symbol(fmu, "fmi2GetReal");
    fmu->getInteger = (fmi2GetIntegerTYPE *)symbol(fmu, "fmi2GetInteger");
    fmu->getBoolean = (fmi2GetBooleanTYPE *)symbol(fmu, "fmi2GetBoolean");
    fmu->doStep = (fmi2DoStepTYPE *)symbol(fmu, "fmi2DoStep");
    fmu->terminate = (fmi2TerminateTYPE *)symbol(fmu, "fmi2Terminate");
    fmu->free_instance = (fmi2FreeInstanceTYPE *)symbol(fmu, "fmi2FreeInstance");
    return 0;
}

#define CHECK(call, what)                                                                      \
    do {                                                                                       \
        fmi2Status status_ = (call);                                                           \
        if (status_ > fmi2Warning) {                                                           \
            fprintf(stderr, "%s of %s failed with status %d\n", what, fmu->name, (int)status_); \
            return 4;                                                                          \
        }                                                                                      \
    } while (0)

static int start(Fmu *fmu) {
    double started = now();
    fmu->component = fmu->instantiate(fmu->name, fmi2CoSimulation, fmu->guid, fmu->uri,
                                      &callbacks, fmi2False, fmi2False);
    fmu->instantiate_s = now() - started;
    if (fmu->component == NULL) {
        fprintf(stderr, "fmi2Instantiate of %s returned NULL\n", fmu->name);
        return 4;
    }
    CHECK(fmu->setup(fmu->component, fmi2False, 0.0, 0.0, fmi2False, 0.0), "fmi2SetupExperiment");
    CHECK(fmu->enter(fmu->component), "fmi2EnterInitializationMode");
    CHECK(fmu->leave(fmu->component), "fmi2ExitInitializationMode");
    return 0;
}

/* Step k: set the inputs, step (time from the integer step count, as the master does), get. */
static int step(Fmu *fmu, size_t k) {
    fmi2Real reals[MAX_PORTS];
    fmi2Integer integers[MAX_PORTS];
    fmi2Boolean booleans[MAX_PORTS];
    const double *in = fmu->inputs + k * (fmu->n[0] + fmu->n[1] + fmu->n[2]);
    for (size_t i = 0; i < fmu->n[0]; i++) reals[i] = *in++;
    for (size_t i = 0; i < fmu->n[1]; i++) integers[i] = (fmi2Integer)*in++;
    for (size_t i = 0; i < fmu->n[2]; i++) booleans[i] = (fmi2Boolean)*in++;
    if (fmu->n[0]) CHECK(fmu->setReal(fmu->component, fmu->vr[0], fmu->n[0], reals), "fmi2SetReal");
    if (fmu->n[1]) CHECK(fmu->setInteger(fmu->component, fmu->vr[1], fmu->n[1], integers), "fmi2SetInteger");
    if (fmu->n[2]) CHECK(fmu->setBoolean(fmu->component, fmu->vr[2], fmu->n[2], booleans), "fmi2SetBoolean");
    CHECK(fmu->doStep(fmu->component, (double)k * fmu->step, fmu->step, fmi2True), "fmi2DoStep");
    if (fmu->n[3]) CHECK(fmu->getReal(fmu->component, fmu->vr[3], fmu->n[3], reals), "fmi2GetReal");
    if (fmu->n[4]) CHECK(fmu->getInteger(fmu->component, fmu->vr[4], fmu->n[4], integers), "fmi2GetInteger");
    if (fmu->n[5]) CHECK(fmu->getBoolean(fmu->component, fmu->vr[5], fmu->n[5], booleans), "fmi2GetBoolean");
    double *out = fmu->outputs + k * (fmu->n[3] + fmu->n[4] + fmu->n[5]);
    for (size_t i = 0; i < fmu->n[3]; i++) *out++ = reals[i];
    for (size_t i = 0; i < fmu->n[4]; i++) *out++ = integers[i];
    for (size_t i = 0; i < fmu->n[5]; i++) *out++ = booleans[i];
    return 0;
}

static int finish(Fmu *fmu) {
    CHECK(fmu->terminate(fmu->component), "fmi2Terminate");
    fmu->free_instance(fmu->component);
    return 0;
}

/* One FMU's whole life in its own thread (--threads). A failed thread still meets the others at
 * both barriers, so that none waits forever. */
static void *run_thread(void *argument) {
    Fmu *fmu = argument;
    int status = load(fmu);
    pthread_barrier_wait(&instantiate_barrier);
    if (status == 0) status = start(fmu);
    for (size_t k = 0; status == 0 && k < n_steps; k++) status = step(fmu, k);
    pthread_barrier_wait(&free_barrier);
    if (status == 0) status = finish(fmu);
    fmu->failed = status;
    return NULL;
}

static int read_plan(Fmu **out, size_t *n_fmus) {
    if (scanf("%zu %zu", n_fmus, &n_steps) != 2 || *n_fmus == 0 || *n_fmus > MAX_FMUS) return 2;
    Fmu *fmus = calloc(*n_fmus, sizeof *fmus);
    *out = fmus;
    for (size_t f = 0; f < *n_fmus; f++) {
        Fmu *fmu = &fmus[f];
        if (scanf("%4095s %255s %4095s %255s %lf", fmu->binary, fmu->guid, fmu->uri, fmu->name,
                  &fmu->step) != 5)
            return 2;
        for (int group = 0; group < 6; group++) {
            if (scanf("%zu", &fmu->n[group]) != 1 || fmu->n[group] > MAX_PORTS) return 2;
            for (size_t i = 0; i < fmu->n[group]; i++)
                if (scanf("%u", &fmu->vr[group][i]) != 1) return 2;
        }
        fmu->inputs = calloc(n_steps * (fmu->n[0] + fmu->n[1] + fmu->n[2]) + 1, sizeof(double));
        fmu->outputs = calloc(n_steps * (fmu->n[3] + fmu->n[4] + fmu->n[5]) + 1, sizeof(double));
    }
    for (size_t k = 0; k < n_steps; k++) {
        for (size_t f = 0; f < *n_fmus; f++) {
            Fmu *fmu = &fmus[f];
            size_t width = fmu->n[0] + fmu->n[1] + fmu->n[2];
            for (size_t i = 0; i < width; i++)
                if (scanf("%lf", &fmu->inputs[k * width + i]) != 1) return 2;
        }
    }
    return 0;
}

static void print_outputs(const Fmu *fmus, size_t n_fmus) {
    for (size_t k = 0; k < n_steps; k++) {
        for (size_t f = 0; f < n_fmus; f++) {
            const Fmu *fmu = &fmus[f];
            const double *out = fmu->outputs + k * (fmu->n[3] + fmu->n[4] + fmu->n[5]);
            printf("%zu %zu", k, f);
            for (size_t i = 0; i < fmu->n[3]; i++) printf(" %.17g", *out++);
            for (size_t i = 0; i < fmu->n[4] + fmu->n[5]; i++) printf(" %d", (int)*out++);
            printf("\n");
        }
    }
}

int main(int argc, char **argv) {
    int keep_loaded = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--keep-loaded") == 0) keep_loaded = 1;
        else if (strcmp(argv[i], "--threads") == 0) threaded = 1;
        else if (strcmp(argv[i], "--timing") == 0) timing = 1;
        else return 2;
    }
    Fmu *fmus = NULL;
    size_t n_fmus = 0;
    int status = read_plan(&fmus, &n_fmus);
    if (status != 0) return status;
    if (threaded) {
        pthread_t threads[MAX_FMUS];
        pthread_barrier_init(&instantiate_barrier, NULL, (unsigned)n_fmus);
        pthread_barrier_init(&free_barrier, NULL, (unsigned)n_fmus);
        for (size_t f = 0; f < n_fmus; f++)
            if (pthread_create(&threads[f], NULL, run_thread, &fmus[f]) != 0) return 3;
        for (size_t f = 0; f < n_fmus; f++) pthread_join(threads[f], NULL);
        for (size_t f = 0; f < n_fmus; f++)
            if (fmus[f].failed) return fmus[f].failed;
    } else {
        for (size_t f = 0; f < n_fmus && status == 0; f++) status = load(&fmus[f]);
        for (size_t f = 0; f < n_fmus && status == 0; f++) status = start(&fmus[f]);
        for (size_t k = 0; k < n_steps && status == 0; k++)
            for (size_t f = 0; f < n_fmus && status == 0; f++) status = step(&fmus[f], k);
        for (size_t f = 0; f < n_fmus && status == 0; f++) status = finish(&fmus[f]);
        if (status != 0) return status;
        for (size_t f = 0; f < n_fmus && timing; f++) { /* once more, now that all is loaded */
            Fmu *fmu = &fmus[f];
            double first = fmu->instantiate_s;
            if ((status = start(fmu)) != 0 || (status = finish(fmu)) != 0) return status;
            fprintf(stderr, "timing %zu first %.9f later %.9f\n", f, first, fmu->instantiate_s);
        }
    }
    print_outputs(fmus, n_fmus);
    for (size_t f = 0; f < n_fmus && !keep_loaded; f++) {
        if (dlclose(fmus[f].library) != 0) {
            fprintf(stderr, "dlclose failed: %s\n", dlerror());
            return 5;
        }
    }
    for (size_t f = 0; f < n_fmus; f++) {
        free(fmus[f].inputs);
        free(fmus[f].outputs);
    }
    free(fmus);
    fflush(stdout);
    return 0;
}
