/* Typed fmi2Get and fmi2Set: ports are read and written as attributes of the slave, by the
 * interned name of the variable (pythonfmu's default getter and setter).
 *
 * One routine gets and one sets for all four types; the type is a constant at each fmi2 entry
 * point, so the compiler specialises the routine per type. Every value reference is checked
 * (known, of the call's type, settable in this state) before any value is touched: a refused call
 * changes nothing. A value the slave cannot give or take is refused naming the call and the
 * variable (and the value, where it is the value that does not fit).
 */
#include <stdio.h>
#include <stdlib.h>

#include "sonotrack_fmi2.h"

/* Check every value reference before touching any (a refused call changes nothing). */
static fmi2Status check_references(Instance *c, const char *function, const fmi2ValueReference vr[],
                                   size_t nvr, int type) {
    if (nvr > 0 && vr == NULL) return refuse(c, "%s: value reference array is NULL", function);
    for (size_t i = 0; i < nvr; i++) {
        if (vr[i] >= c->binding.nvars || c->binding.vars[vr[i]].type == T_NONE)
            return refuse(c, "%s: unknown value reference %u", function, (unsigned)vr[i]);
        const Variable *v = &c->binding.vars[vr[i]];
        if (v->type != type)
            return refuse(c, "%s: variable %s (value reference %u) is %s, not %s", function,
                          v->name, (unsigned)vr[i], TYPE_NAMES[v->type], TYPE_NAMES[type]);
    }
    return fmi2OK;
}

/* FMI 2.0 rules for fmi2Set<type>: before initialisation ends, parameters, inputs and variables
 * with an exact or approx start; afterwards only inputs and tunable parameters. */
static fmi2Status check_settable(Instance *c, const char *function, const fmi2ValueReference vr[],
                                 size_t nvr) {
    for (size_t i = 0; i < nvr; i++) {
        const Variable *v = &c->binding.vars[vr[i]];
        const char *why = NULL;
        if (v->variability == V_CONSTANT) why = "a constant";
        else if (v->causality == C_OUTPUT) why = "an output";
        else if (v->causality == C_CALCULATED) why = "a calculated parameter";
        else if (v->causality == C_INDEPENDENT) why = "the independent variable";
        else if (c->mode == M_STEP_COMPLETE) {
            if (v->causality == C_PARAMETER && v->variability != V_TUNABLE)
                why = "a fixed parameter: it can be set only before fmi2ExitInitializationMode";
            else if (v->causality != C_INPUT && v->causality != C_PARAMETER)
                why = "not an input: it can be set only before fmi2ExitInitializationMode";
        } else if (v->causality == C_LOCAL && v->initial != I_EXACT && v->initial != I_APPROX) {
            why = "a calculated local variable";
        }
        if (why != NULL)
            return refuse(c, "%s: variable %s (value reference %u) is %s", function, v->name,
                          (unsigned)vr[i], why);
    }
    return fmi2OK;
}

/* The pending Python error of reading or writing a variable, as an FMI status (GIL held). */
static fmi2Status attribute_failure(Instance *c, const char *function, const Variable *v) {
    char what[512];
    snprintf(what, sizeof what, "variable %s", v->name);
    return python_failure(c, function, what);
}

/* fmi2Get<type>: value is an array of fmi2Real, fmi2Integer, fmi2Boolean or fmi2String. */
static inline __attribute__((always_inline)) fmi2Status
get_values(fmi2Component component, const char *function, int type,
           const fmi2ValueReference vr[], size_t nvr, void *value) {
    INSTANCE(function);
    REQUIRE(function, M_GET);
    if (check_references(c, function, vr, nvr, type) != fmi2OK) return fmi2Error;
    if (nvr > 0 && value == NULL) return refuse(c, "%s: value array is NULL", function);
    int gil = py.GILEnsure();
    if (type == T_STRING) { /* the strings stay alive until the next fmi2GetString */
        release_strings(c);
        c->strings = calloc(nvr ? nvr : 1, sizeof *c->strings);
        if (c->strings == NULL) {
            py.GILRelease(gil);
            return refuse(c, "%s: out of memory", function);
        }
        c->nstrings = nvr;
    }
    for (size_t i = 0; i < nvr; i++) {
        const Variable *v = &c->binding.vars[vr[i]];
        PyObject *object = py.GetAttr(c->slave, v->attribute);
        int failed = 0;
        long integer = 0;
        switch (type) {
        case T_REAL: {
            double number = object ? py.FloatAsDouble(object) : -1.0;
            failed = number == -1.0 && py.ErrOccurred();
            if (!failed) ((fmi2Real *)value)[i] = number;
            break;
        }
        case T_INTEGER:
            integer = object ? py.LongAsLong(object) : -1;
            failed = integer == -1 && py.ErrOccurred();
            if (!failed && integer >= INT32_MIN && integer <= INT32_MAX)
                ((fmi2Integer *)value)[i] = (fmi2Integer)integer;
            break;
        case T_BOOLEAN: {
            int truth = object ? py.IsTrue(object) : -1;
            failed = truth < 0;
            if (!failed) ((fmi2Boolean *)value)[i] = truth ? fmi2True : fmi2False;
            break;
        }
        default: { /* T_STRING */
            PyObject *text = object ? py.Str(object) : NULL;
            const char *utf8 = text ? py.UnicodeAsUTF8(text) : NULL;
            failed = utf8 == NULL;
            if (failed) {
                if (text) py.DecRef(text);
            } else {
                c->strings[i] = text; /* utf8 lives as long as text */
                ((fmi2String *)value)[i] = utf8;
            }
        }
        }
        if (object) py.DecRef(object);
        if (failed) {
            fmi2Status status = attribute_failure(c, function, v);
            py.GILRelease(gil);
            return status;
        }
        if (type == T_INTEGER && (integer < INT32_MIN || integer > INT32_MAX)) {
            py.GILRelease(gil);
            return refuse(c, "%s: variable %s = %ld does not fit an fmi2Integer", function,
                          v->name, integer);
        }
    }
    py.GILRelease(gil);
    return fmi2OK;
}

/* fmi2Set<type>: value is an array of fmi2Real, fmi2Integer, fmi2Boolean or fmi2String. */
static inline __attribute__((always_inline)) fmi2Status
set_values(fmi2Component component, const char *function, int type,
           const fmi2ValueReference vr[], size_t nvr, const void *value) {
    INSTANCE(function);
    REQUIRE(function, M_SET);
    if (check_references(c, function, vr, nvr, type) != fmi2OK) return fmi2Error;
    if (check_settable(c, function, vr, nvr) != fmi2OK) return fmi2Error;
    if (nvr > 0 && value == NULL) return refuse(c, "%s: value array is NULL", function);
    if (type == T_STRING) {
        for (size_t i = 0; i < nvr; i++)
            if (((const fmi2String *)value)[i] == NULL)
                return refuse(c, "%s: NULL string for variable %s", function,
                              c->binding.vars[vr[i]].name);
    }
    int gil = py.GILEnsure();
    for (size_t i = 0; i < nvr; i++) {
        const Variable *v = &c->binding.vars[vr[i]];
        PyObject *object;
        switch (type) {
        case T_REAL: object = py.FloatFromDouble(((const fmi2Real *)value)[i]); break;
        case T_INTEGER: object = py.LongFromLong(((const fmi2Integer *)value)[i]); break;
        case T_BOOLEAN: object = py.BoolFromLong(((const fmi2Boolean *)value)[i] != fmi2False);
            break;
        default: object = py.UnicodeFromString(((const fmi2String *)value)[i]); /* T_STRING */
        }
        int failed = object == NULL || py.SetAttr(c->slave, v->attribute, object) != 0;
        if (object) py.DecRef(object);
        if (failed) {
            fmi2Status status = attribute_failure(c, function, v);
            py.GILRelease(gil);
            return status;
        }
    }
    py.GILRelease(gil);
    return fmi2OK;
}

/* The eight typed entry points: fmi2GetReal, fmi2SetReal, fmi2GetInteger, fmi2SetInteger,
 * fmi2GetBoolean, fmi2SetBoolean, fmi2GetString and fmi2SetString. */
#define TYPED_ACCESS(Type, type)                                                               \
    fmi2Status fmi2Get##Type(fmi2Component component, const fmi2ValueReference vr[],           \
                             size_t nvr, fmi2##Type value[]) {                                 \
        return get_values(component, "fmi2Get" #Type, type, vr, nvr, value);                  \
    }                                                                                          \
    fmi2Status fmi2Set##Type(fmi2Component component, const fmi2ValueReference vr[],           \
                             size_t nvr, const fmi2##Type value[]) {                           \
        return set_values(component, "fmi2Set" #Type, type, vr, nvr, value);                  \
    }

TYPED_ACCESS(Real, T_REAL)
TYPED_ACCESS(Integer, T_INTEGER)
TYPED_ACCESS(Boolean, T_BOOLEAN)
TYPED_ACCESS(String, T_STRING)
