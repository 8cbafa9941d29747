/* fmi2DoStep, and the calls this FMU does not support (each refused with a message saying why).
 *
 * do_step returning True is fmi2OK; False is fmi2Discard (the slave logged why; the instance is
 * in stepFailed, from which an FMU state can be restored); an exception maps through
 * python_failure; any other return value is a bug in the slave and gives fmi2Error naming it.
 * A communication point that is not finite, or a step size that is not positive and finite, is
 * refused here, before the model sees it: every FMU gets the same check and the same message.
 */
#include <math.h>

#include "sonotrack_fmi2.h"

fmi2Status fmi2DoStep(fmi2Component component, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    INSTANCE("fmi2DoStep");
    REQUIRE("fmi2DoStep", M_STEP_COMPLETE);
    if (!isfinite(currentCommunicationPoint))
        return refuse(c, "fmi2DoStep: currentCommunicationPoint = %g is not a finite time",
                      currentCommunicationPoint);
    if (!isfinite(communicationStepSize) || !(communicationStepSize > 0.0))
        return refuse(c, "fmi2DoStep: communicationStepSize = %.17g must be positive and finite",
                      communicationStepSize);
    int gil = py.GILEnsure();
    PyObject *time = py.FloatFromDouble(currentCommunicationPoint);
    PyObject *step = py.FloatFromDouble(communicationStepSize);
    PyObject *result = (time && step) ? py.CallArgs(c->do_step, time, step, NULL) : NULL;
    if (time) py.DecRef(time);
    if (step) py.DecRef(step);
    fmi2Status status;
    if (result == NULL) {
        status = python_failure(c, "fmi2DoStep", "do_step");
    } else {
        if (py.ListSize(c->log_queue) > 0) drain_log(c);
        if (result == py.True) {
            status = fmi2OK;
        } else if (result == py.False) {
            status = fmi2Discard; /* the slave refused the step and logged why */
            c->mode = M_STEP_FAILED;
        } else {
            PyObject *text = py.Repr(result);
            const char *utf8 = text ? py.UnicodeAsUTF8(text) : NULL;
            status = refuse(c, "fmi2DoStep: do_step returned %.100s; it must return True (step "
                            "done) or False (step refused)", utf8 ? utf8 : "?");
            if (text) py.DecRef(text);
            if (py.ErrOccurred()) py.ErrClear();
        }
        py.DecRef(result);
    }
    py.GILRelease(gil);
    return status;
}

fmi2Status fmi2CancelStep(fmi2Component component) {
    INSTANCE("fmi2CancelStep");
    return refuse(c, "fmi2CancelStep: not supported (fmi2DoStep is synchronous: no step is ever "
                  "pending)");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component component, const fmi2ValueReference vr[],
                                       size_t nvr, const fmi2Integer order[],
                                       const fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    INSTANCE("fmi2SetRealInputDerivatives");
    return refuse(c, "fmi2SetRealInputDerivatives: not supported (canInterpolateInputs=false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component component, const fmi2ValueReference vr[],
                                        size_t nvr, const fmi2Integer order[], fmi2Real value[]) {
    (void)vr; (void)nvr; (void)order; (void)value;
    INSTANCE("fmi2GetRealOutputDerivatives");
    return refuse(c, "fmi2GetRealOutputDerivatives: not supported (maxOutputDerivativeOrder=0)");
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component component,
                                        const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown;
    (void)dvUnknown;
    INSTANCE("fmi2GetDirectionalDerivative");
    return refuse(c, "fmi2GetDirectionalDerivative: not supported "
                  "(providesDirectionalDerivative=false)");
}

static fmi2Status no_status(Instance *c, const char *function) {
    return refuse(c, "%s: not supported (asynchronous stepping is not provided)", function);
}

fmi2Status fmi2GetStatus(fmi2Component component, const fmi2StatusKind s, fmi2Status *value) {
    (void)s; (void)value;
    INSTANCE("fmi2GetStatus");
    return no_status(c, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component component, const fmi2StatusKind s, fmi2Real *value) {
    (void)s; (void)value;
    INSTANCE("fmi2GetRealStatus");
    return no_status(c, "fmi2GetRealStatus");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component component, const fmi2StatusKind s,
                                fmi2Integer *value) {
    (void)s; (void)value;
    INSTANCE("fmi2GetIntegerStatus");
    return no_status(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component component, const fmi2StatusKind s,
                                fmi2Boolean *value) {
    INSTANCE("fmi2GetBooleanStatus");
    if (s == fmi2Terminated && value != NULL) { /* the slaves never end a simulation early */
        *value = fmi2False;
        return fmi2OK;
    }
    return no_status(c, "fmi2GetBooleanStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component component, const fmi2StatusKind s,
                               fmi2String *value) {
    (void)s; (void)value;
    INSTANCE("fmi2GetStringStatus");
    return no_status(c, "fmi2GetStringStatus");
}
