/* Instances and the FMI 2.0 co-simulation state machine: instantiate, free, reset, debug
 * logging, setup, enter/exit initialisation and terminate.
 *
 * States follow the FMI 2.0 co-simulation state table (instantiated, initializationMode,
 * stepComplete, stepFailed, terminated, error); each fmi2 function names the states it is
 * allowed in (REQUIRE) and a call in another state is refused with a message listing them.
 */
#define _GNU_SOURCE
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sonotrack_fmi2.h"

#ifndef SONOTRACK_SOURCE_SHA256
#error "define SONOTRACK_SOURCE_SHA256 as the quoted orchestrator.builder.fmi_binary.source_hash() (make does)"
#endif

/* Which sources this library was compiled from: `sonotrack build` reads the string from the file
 * and refuses a library whose sources have changed since (orchestrator.builder.fmi_binary). */
__attribute__((used, retain)) static const char SOURCE_ID[] =
    "sonotrack-fmi2-sources sha256 " SONOTRACK_SOURCE_SHA256;

/* The slave and its bound methods, as make() in the Python helpers returns them. */
#define SLAVE_FIELDS(c)                                                                        \
    {&(c)->slave, &(c)->do_step, &(c)->log_queue, &(c)->setup, &(c)->enter, &(c)->exit,        \
     &(c)->terminate, &(c)->get_state, &(c)->set_state, &(c)->to_bytes, &(c)->from_bytes}

static const char *mode_name(int mode) {
    switch (mode) {
    case M_INSTANTIATED: return "instantiated";
    case M_INIT: return "initializationMode";
    case M_STEP_COMPLETE: return "stepComplete";
    case M_STEP_FAILED: return "stepFailed";
    case M_TERMINATED: return "terminated";
    case M_ERROR: return "error";
    default: return "unknown";
    }
}

fmi2Status wrong_state(Instance *c, const char *function, int allowed) {
    char list[256] = "";
    static const int modes[] = {M_INSTANTIATED, M_INIT, M_STEP_COMPLETE, M_STEP_FAILED,
                                M_TERMINATED, M_ERROR};
    for (size_t i = 0; i < sizeof modes / sizeof modes[0]; i++) {
        if (allowed & modes[i]) {
            if (list[0]) strcat(list, ", ");
            strcat(list, mode_name(modes[i]));
        }
    }
    return refuse(c, "%s: not allowed in state %s (allowed in: %s)", function, mode_name(c->mode),
                  list);
}

void release_strings(Instance *c) {
    for (size_t i = 0; i < c->nstrings; i++)
        if (c->strings[i]) py.DecRef(c->strings[i]);
    free(c->strings);
    c->strings = NULL;
    c->nstrings = 0;
}

static void drop_slave(Instance *c) {
    PyObject **fields[] = SLAVE_FIELDS(c);
    for (size_t i = 0; i < sizeof fields / sizeof fields[0]; i++) {
        if (*fields[i]) py.DecRef(*fields[i]);
        *fields[i] = NULL;
    }
}

/* Create the slave object (GIL held); on failure the reason is logged. */
static int make_slave(Instance *c) {
    PyObject *name = py.UnicodeFromString(c->name);
    PyObject *resources = py.UnicodeFromString(c->resources);
    PyObject *visible = py.BoolFromLong(c->visible);
    PyObject *made = (name && resources && visible)
                         ? py.CallArgs(g_make, c->cls, name, resources, visible, NULL) : NULL;
    if (name) py.DecRef(name);
    if (resources) py.DecRef(resources);
    if (visible) py.DecRef(visible);
    if (made == NULL) return -1;
    PyObject **fields[] = SLAVE_FIELDS(c);
    for (Py_ssize_t_ i = 0; i < (Py_ssize_t_)(sizeof fields / sizeof fields[0]); i++) {
        *fields[i] = py.TupleGetItem(made, i);
        py.IncRef(*fields[i]);
    }
    py.DecRef(made);
    drain_log(c);
    return 0;
}

static void free_instance(Instance *c, int python_alive) {
    free_binding(&c->binding, python_alive);
    free(c->name);
    free(c->resources);
    free(c);
}

/* A refused instantiation also goes to stderr, in one write: some hosts (ecos) log the
 * refusal at debug level only, then fail on the NULL instance, and the user sees no reason. */
static void to_stderr(const char *instance, const char *message) {
    size_t size = strlen(instance) + strlen(message) + 32;
    char *line = malloc(size);
    if (line == NULL) return;
    int n = snprintf(line, size, "sonotrack FMU %s: %s\n", instance, message);
    if (n > 0 && write(2, line, (size_t)n) < 0) { /* nothing more to do: stderr is gone */ }
    free(line);
}

/* ----- FMI 2.0: common functions ----------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn) {
    fmi2CallbackLogger logger = functions ? functions->logger : NULL;
    fmi2ComponentEnvironment environment = functions ? functions->componentEnvironment : NULL;
    const char *name = instanceName ? instanceName : "";
    char error[8192] = ""; /* the search for Python names every place it tried */
#define FAIL(...)                                                                              \
    do {                                                                                       \
        snprintf(error, sizeof error, __VA_ARGS__);                                            \
        goto failed;                                                                           \
    } while (0)
    Instance *c = calloc(1, sizeof *c);
    if (c == NULL) FAIL("fmi2Instantiate: out of memory");
    c->name = strdup(name);
    c->logger = logger;
    c->environment = environment;
    c->logging_on = loggingOn ? 1 : 0;
    c->categories = CAT_EVERY;
    c->visible = visible ? 1 : 0;
    c->mode = M_INSTANTIATED;
    if (FATAL()) FAIL("fmi2Instantiate: the Python interpreter failed earlier in this process");
    if (instanceName == NULL || instanceName[0] == '\0')
        FAIL("fmi2Instantiate: instanceName must be a non-empty string");
    if (fmuType != fmi2CoSimulation)
        FAIL("fmi2Instantiate: this FMU supports Co-Simulation only (fmuType %d)", (int)fmuType);
    c->resources = (fmuResourceLocation && fmuResourceLocation[0])
                       ? path_from_uri(fmuResourceLocation) : resources_beside_binary();
    if (c->resources == NULL) FAIL("fmi2Instantiate: no resource location");
    char table[4096];
    snprintf(table, sizeof table, "%s/sonotrack_binding.txt", c->resources);
    if (read_binding(table, &c->binding, error + 17, sizeof error - 17)) {
        memcpy(error, "fmi2Instantiate: ", 17);
        goto failed;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, c->binding.guid) != 0)
        FAIL("fmi2Instantiate: GUID %s does not match this FMU's %s (modelDescription.xml of a "
             "different build?)", fmuGUID ? fmuGUID : "(null)", c->binding.guid);
    if (ensure_python(&c->binding, error + 17, sizeof error - 17) != 0) {
        memcpy(error, "fmi2Instantiate: ", 17);
        goto failed;
    }
    int gil = py.GILEnsure();
    const char *version = py.GetVersion();
    size_t length = strlen(c->binding.python_version);
    if (strncmp(version, c->binding.python_version, length) != 0 ||
        (version[length] >= '0' && version[length] <= '9'))
        logf_(c, fmi2Warning, "fmi2Instantiate: built for Python %s, running in Python %.20s",
              c->binding.python_version, version);
    PyObject *resources = py.UnicodeFromString(c->resources);
    PyObject *package = py.UnicodeFromString(c->binding.package);
    PyObject *entry = py.UnicodeFromString(c->binding.entry);
    PyObject *class_name = py.UnicodeFromString(c->binding.class_name);
    c->cls = py.CallArgs(g_load_class, resources, package, entry, class_name, NULL);
    py.DecRef(resources); py.DecRef(package); py.DecRef(entry); py.DecRef(class_name);
    int made = c->cls != NULL && make_slave(c) == 0;
    for (size_t i = 0; made && i < c->binding.nvars; i++) {
        Variable *v = &c->binding.vars[i];
        if (v->type != T_NONE && (v->attribute = py.InternFromString(v->name)) == NULL) made = 0;
    }
    if (!made) {
        char text[1536];
        exception_text(text, sizeof text);
        snprintf(error, sizeof error, "fmi2Instantiate: cannot load the model %s from %s: %s",
                 c->binding.class_name, c->resources, text);
        drop_slave(c);
        if (c->cls) py.DecRef(c->cls);
        c->cls = NULL;
        free_binding(&c->binding, 1); /* its interned names are dropped with the GIL held */
        py.GILRelease(gil);
        goto failed;
    }
    py.GILRelease(gil);
    return c;
failed:
    emit(logger, environment, name, 1, CAT_ALL, fmi2Error, "logStatusError", error);
    to_stderr(name, error);
    if (c) free_instance(c, 0); /* no Python object is left in it by now */
    return NULL;
#undef FAIL
}

void fmi2FreeInstance(fmi2Component component) {
    Instance *c = (Instance *)component;
    if (c == NULL) return;
    if (FATAL()) { /* never touch a failed interpreter; the Python objects leak */
        free_instance(c, 0);
        return;
    }
    int gil = py.GILEnsure();
    release_strings(c);
    drop_slave(c);
    if (c->cls) py.DecRef(c->cls);
    free_instance(c, 1);
    py.GILRelease(gil);
}

fmi2Status fmi2SetDebugLogging(fmi2Component component, fmi2Boolean loggingOn,
                               size_t nCategories, const fmi2String categories[]) {
    INSTANCE("fmi2SetDebugLogging");
    int mask = 0;
    for (size_t i = 0; i < nCategories; i++) {
        int index = categories[i] ? lookup(categories[i], CATEGORY_NAMES, 5) : -1;
        if (index < 0)
            return refuse(c, "fmi2SetDebugLogging: unknown log category %s (valid: logStatusWarning,"
                          " logStatusDiscard, logStatusError, logStatusFatal, logAll)",
                          categories[i] ? categories[i] : "(null)");
        mask |= 1 << index;
    }
    c->logging_on = loggingOn ? 1 : 0;
    c->categories = nCategories ? mask : CAT_EVERY;
    return fmi2OK;
}

/* Status of an initialisation call from the slave's return value (GIL held): None or True is
 * fine, False is a refusal (pythonfmu ignores both). */
static fmi2Status init_result(Instance *c, PyObject *result, const char *function,
                              const char *method) {
    if (result == NULL) return python_failure(c, function, method);
    int refused = result == py.False;
    py.DecRef(result);
    drain_log(c);
    if (refused) return refuse(c, "%s: %s returned False", function, method);
    return fmi2OK;
}

/* Call a lifecycle method of the slave (no arguments); if it succeeds, enter state ``next``. */
static fmi2Status transition(Instance *c, const char *function, PyObject *method,
                             const char *method_name, int next) {
    int gil = py.GILEnsure();
    fmi2Status status = init_result(c, py.CallObject(method, NULL), function, method_name);
    if (status == fmi2OK) c->mode = next;
    py.GILRelease(gil);
    return status;
}

fmi2Status fmi2SetupExperiment(fmi2Component component, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    INSTANCE("fmi2SetupExperiment");
    REQUIRE("fmi2SetupExperiment", M_INSTANTIATED);
    if (!isfinite(startTime))
        return refuse(c, "fmi2SetupExperiment: startTime = %g is not a finite time", startTime);
    if (stopTimeDefined && !(isfinite(stopTime) && stopTime >= startTime))
        return refuse(c, "fmi2SetupExperiment: stopTime = %.17g must be finite and not before "
                      "startTime = %.17g", stopTime, startTime);
    int gil = py.GILEnsure();
    PyObject *start = py.FloatFromDouble(startTime);
    PyObject *stop = stopTimeDefined ? py.FloatFromDouble(stopTime) : (py.IncRef(py.None), py.None);
    PyObject *tol = toleranceDefined ? py.FloatFromDouble(tolerance) : (py.IncRef(py.None), py.None);
    PyObject *result = (start && stop && tol) ? py.CallArgs(c->setup, start, stop, tol, NULL) : NULL;
    if (start) py.DecRef(start);
    if (stop) py.DecRef(stop);
    if (tol) py.DecRef(tol);
    fmi2Status status = init_result(c, result, "fmi2SetupExperiment", "setup_experiment");
    if (status == fmi2OK) c->setup_done = 1;
    py.GILRelease(gil);
    return status;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component component) {
    INSTANCE("fmi2EnterInitializationMode");
    REQUIRE("fmi2EnterInitializationMode", M_INSTANTIATED);
    if (!c->setup_done)
        return refuse(c, "fmi2EnterInitializationMode: fmi2SetupExperiment must be called first");
    return transition(c, "fmi2EnterInitializationMode", c->enter, "enter_initialization_mode",
                      M_INIT);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component component) {
    INSTANCE("fmi2ExitInitializationMode");
    REQUIRE("fmi2ExitInitializationMode", M_INIT);
    return transition(c, "fmi2ExitInitializationMode", c->exit, "exit_initialization_mode",
                      M_STEP_COMPLETE);
}

fmi2Status fmi2Terminate(fmi2Component component) {
    INSTANCE("fmi2Terminate");
    REQUIRE("fmi2Terminate", M_STEP_COMPLETE | M_STEP_FAILED);
    return transition(c, "fmi2Terminate", c->terminate, "terminate", M_TERMINATED);
}

fmi2Status fmi2Reset(fmi2Component component) {
    INSTANCE("fmi2Reset");
    REQUIRE("fmi2Reset", M_ANY);
    int gil = py.GILEnsure();
    release_strings(c);
    drop_slave(c);
    fmi2Status status = fmi2OK;
    if (make_slave(c) != 0) status = python_failure(c, "fmi2Reset", "creating the slave");
    if (status == fmi2OK) {
        c->mode = M_INSTANTIATED;
        c->setup_done = 0;
    }
    py.GILRelease(gil);
    return status;
}
