/* Logging to the host and mapping Python exceptions to FMI statuses.
 *
 * A message with a status above fmi2OK always reaches the host's logger (a refusal never loses
 * its reason); fmi2OK messages only when logging is on. A refusal (refuse) is logged and puts the
 * instance into the error state; python_failure maps the pending Python exception of a call on
 * the slave to fmi2Discard, fmi2Error or fmi2Fatal.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sonotrack_fmi2.h"

const char *const CATEGORY_NAMES[5] = {"logStatusWarning", "logStatusDiscard", "logStatusError",
                                       "logStatusFatal", "logAll"};

static int category_of_status(fmi2Status status) {
    switch (status) {
    case fmi2Warning: return CAT_WARNING;
    case fmi2Discard: return CAT_DISCARD;
    case fmi2Error: return CAT_ERROR;
    case fmi2Fatal: return CAT_FATAL;
    default: return CAT_ALL;
    }
}

/* Messages with a status above OK always reach the host (a refusal must never lose its
 * reason); OK messages only when logging is on for their category. */
void emit(fmi2CallbackLogger logger, fmi2ComponentEnvironment environment,
          const char *instance, int logging_on, int categories, fmi2Status status,
          const char *category, const char *message) {
    if (logger == NULL) return;
    if (status == fmi2OK && !(logging_on && (categories & CAT_ALL))) return;
    if (category == NULL) category = CATEGORY_NAMES[__builtin_ctz((unsigned)category_of_status(status))];
    if (strchr(message, '%') == NULL) {
        logger(environment, instance, status, category, message);
        return;
    }
    /* The logger takes a printf format: escape '%' so a message is shown as written. */
    size_t n = strlen(message), extra = 0;
    for (size_t i = 0; i < n; i++) extra += message[i] == '%';
    char *escaped = malloc(n + extra + 1);
    if (escaped == NULL) return;
    char *out = escaped;
    for (size_t i = 0; i < n; i++) {
        *out++ = message[i];
        if (message[i] == '%') *out++ = '%';
    }
    *out = '\0';
    logger(environment, instance, status, category, escaped);
    free(escaped);
}

static void vlog(Instance *c, fmi2Status status, const char *format, va_list args)
    __attribute__((format(printf, 3, 0)));

static void vlog(Instance *c, fmi2Status status, const char *format, va_list args) {
    char buffer[2048];
    vsnprintf(buffer, sizeof buffer, format, args);
    emit(c->logger, c->environment, c->name, c->logging_on, c->categories, status, NULL, buffer);
}

void logf_(Instance *c, fmi2Status status, const char *format, ...) {
    va_list args;
    va_start(args, format);
    vlog(c, status, format, args);
    va_end(args);
}

/* An fmi2Error refusal: logged, and the instance enters the error state. */
fmi2Status refuse(Instance *c, const char *format, ...) {
    va_list args;
    va_start(args, format);
    vlog(c, fmi2Error, format, args);
    va_end(args);
    c->mode = M_ERROR;
    return fmi2Error;
}

/* Forward the slave's queued log messages to the host (GIL held). */
void drain_log(Instance *c) {
    if (c->log_queue == NULL || py.ListSize(c->log_queue) <= 0) {
        if (py.ErrOccurred()) py.ErrClear();
        return;
    }
    PyObject *items = py.CallArgs(g_drain, c->log_queue, NULL);
    if (items == NULL) {
        py.ErrClear();
        return;
    }
    Py_ssize_t_ n = py.ListSize(items);
    for (Py_ssize_t_ i = 0; i < n; i++) {
        PyObject *item = py.ListGetItem(items, i);
        long status = py.LongAsLong(py.TupleGetItem(item, 0));
        const char *category = py.UnicodeAsUTF8(py.TupleGetItem(item, 1));
        const char *message = py.UnicodeAsUTF8(py.TupleGetItem(item, 2));
        if (category != NULL && message != NULL && status >= fmi2OK && status <= fmi2Fatal)
            emit(c->logger, c->environment, c->name, c->logging_on, c->categories,
                 (fmi2Status)status, category, message);
    }
    if (py.ErrOccurred()) py.ErrClear();
    py.DecRef(items);
}

/* Text of the pending exception, for failures outside the model (GIL held, clears it). */
void exception_text(char *out, size_t size) {
    PyObject *type = NULL, *value = NULL, *trace = NULL;
    py.ErrFetch(&type, &value, &trace);
    py.ErrNormalize(&type, &value, &trace);
    snprintf(out, size, "unknown Python error");
    if (value != NULL) {
        PyObject *text = py.Repr(value);
        const char *utf8 = text ? py.UnicodeAsUTF8(text) : NULL;
        if (utf8 != NULL) snprintf(out, size, "%s", utf8);
        if (text) py.DecRef(text);
    }
    if (py.ErrOccurred()) py.ErrClear();
    if (type) py.DecRef(type);
    if (value) py.DecRef(value);
    if (trace) py.DecRef(trace);
}

/* Map the pending Python exception of a call on the slave to an FMI status (GIL held):
 * StepRejectedError -> fmi2Discard, SonotrackError and other exceptions -> fmi2Error,
 * SystemExit/KeyboardInterrupt/MemoryError or a failure to classify -> fmi2Fatal. */
fmi2Status python_failure(Instance *c, const char *function, const char *what) {
    PyObject *type = NULL, *value = NULL, *trace = NULL;
    py.ErrFetch(&type, &value, &trace);
    py.ErrNormalize(&type, &value, &trace);
    drain_log(c); /* the model's own lines came first */
    fmi2Status status = fmi2Fatal;
    char message[4096];
    snprintf(message, sizeof message, "%s: %s: Python error could not be described", function,
             what);
    PyObject *package = py.UnicodeFromString(c->binding.package);
    PyObject *result = (value && package) ? py.CallArgs(g_classify, value, package, NULL) : NULL;
    if (result != NULL && py.TupleSize(result) == 2) {
        long code = py.LongAsLong(py.TupleGetItem(result, 0));
        const char *text = py.UnicodeAsUTF8(py.TupleGetItem(result, 1));
        if (text != NULL && code >= fmi2Discard && code <= fmi2Fatal) {
            status = (fmi2Status)code;
            snprintf(message, sizeof message, "%s: %s: %s", function, what, text);
        }
    }
    if (py.ErrOccurred()) py.ErrClear();
    if (result) py.DecRef(result);
    if (package) py.DecRef(package);
    if (type) py.DecRef(type);
    if (value) py.DecRef(value);
    if (trace) py.DecRef(trace);
    emit(c->logger, c->environment, c->name, c->logging_on, c->categories, status, NULL, message);
    if (status == fmi2Error) c->mode = M_ERROR;
    if (status == fmi2Discard) c->mode = M_STEP_FAILED;
    if (status == fmi2Fatal) SET_FATAL();
    return status;
}
