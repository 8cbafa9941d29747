/* FMU states: fmi2Get/Set/FreeFMUstate and their serialized form.
 *
 * A state keeps the slave's _get_fmu_state() dict and the state machine's state (restoring it
 * also restores the state machine, so a refused step can be retried). Serialized: a 32-byte
 * header (magic, version, state, payload length, a hash of the GUID), then the slave's
 * _fmu_state_to_bytes. A wrong magic, version, GUID, length or payload is fmi2Error
 * ("corrupted state"), never fmi2Fatal.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sonotrack_fmi2.h"

#define STATE_MAGIC 0x534b5453u /* "STKS" */
#define STATE_VERSION 1u
#define STATE_HEADER 32

typedef struct {
    uint32_t magic;
    int mode;
    PyObject *data;  /* the slave's state dict */
    PyObject *bytes; /* its serialized form, made on demand */
} State;

static uint64_t guid_hash(const char *guid) { /* FNV-1a: a state of another FMU is refused */
    uint64_t hash = 1469598103934665603ull;
    for (; *guid; guid++) hash = (hash ^ (unsigned char)*guid) * 1099511628211ull;
    return hash;
}

static State *as_state(fmi2FMUstate s) {
    State *state = (State *)s;
    return (state != NULL && state->magic == STATE_MAGIC) ? state : NULL;
}

static void clear_state(State *state) {
    if (state->data) py.DecRef(state->data);
    if (state->bytes) py.DecRef(state->bytes);
    state->data = state->bytes = NULL;
}

fmi2Status fmi2GetFMUstate(fmi2Component component, fmi2FMUstate *FMUstate) {
    INSTANCE("fmi2GetFMUstate");
    REQUIRE("fmi2GetFMUstate", M_ANY);
    if (FMUstate == NULL) return refuse(c, "fmi2GetFMUstate: FMUstate pointer is NULL");
    State *state = NULL;
    if (*FMUstate != NULL && (state = as_state(*FMUstate)) == NULL)
        return refuse(c, "fmi2GetFMUstate: *FMUstate is not a state of this FMU");
    int gil = py.GILEnsure();
    PyObject *data = py.CallObject(c->get_state, NULL);
    if (data == NULL) {
        fmi2Status status = python_failure(c, "fmi2GetFMUstate", "_get_fmu_state");
        py.GILRelease(gil);
        return status;
    }
    drain_log(c);
    if (state == NULL) state = calloc(1, sizeof *state);
    if (state == NULL) {
        py.DecRef(data);
        py.GILRelease(gil);
        return refuse(c, "fmi2GetFMUstate: out of memory");
    }
    clear_state(state);
    state->magic = STATE_MAGIC;
    state->mode = c->mode;
    state->data = data;
    py.GILRelease(gil);
    *FMUstate = state;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component component, fmi2FMUstate FMUstate) {
    INSTANCE("fmi2SetFMUstate");
    REQUIRE("fmi2SetFMUstate", M_ANY);
    State *state = as_state(FMUstate);
    if (state == NULL) return refuse(c, "fmi2SetFMUstate: not a state of this FMU");
    int gil = py.GILEnsure();
    PyObject *result = py.CallArgs(c->set_state, state->data, NULL);
    fmi2Status status = fmi2OK;
    if (result == NULL) {
        status = python_failure(c, "fmi2SetFMUstate", "_set_fmu_state");
    } else {
        py.DecRef(result);
        drain_log(c);
        c->mode = state->mode; /* the state machine is part of the state */
        if (state->mode != M_INSTANTIATED) c->setup_done = 1;
    }
    py.GILRelease(gil);
    return status;
}

fmi2Status fmi2FreeFMUstate(fmi2Component component, fmi2FMUstate *FMUstate) {
    INSTANCE("fmi2FreeFMUstate");
    if (FMUstate == NULL || *FMUstate == NULL) return fmi2OK;
    State *state = as_state(*FMUstate);
    if (state == NULL) return refuse(c, "fmi2FreeFMUstate: not a state of this FMU");
    int gil = py.GILEnsure();
    clear_state(state);
    py.GILRelease(gil);
    state->magic = 0;
    free(state);
    *FMUstate = NULL;
    return fmi2OK;
}

/* The slave's serialized state (made on first use, kept with the state): data and length. The
 * bytes object stays alive as long as the state, so its buffer can be read without the GIL. */
static fmi2Status state_payload(Instance *c, const char *function, State *state,
                                const char **data, size_t *length) {
    int gil = py.GILEnsure();
    if (state->bytes == NULL) state->bytes = py.CallArgs(c->to_bytes, state->data, NULL);
    if (state->bytes == NULL) {
        fmi2Status status = python_failure(c, function, "_fmu_state_to_bytes");
        py.GILRelease(gil);
        return status;
    }
    char *buffer;
    Py_ssize_t_ size;
    py.BytesAsStringAndSize(state->bytes, &buffer, &size);
    py.GILRelease(gil);
    *data = buffer;
    *length = (size_t)size;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component component, fmi2FMUstate FMUstate,
                                      size_t *size) {
    INSTANCE("fmi2SerializedFMUstateSize");
    State *state = as_state(FMUstate);
    if (state == NULL || size == NULL)
        return refuse(c, "fmi2SerializedFMUstateSize: not a state of this FMU");
    const char *data;
    size_t length;
    fmi2Status status = state_payload(c, "fmi2SerializedFMUstateSize", state, &data, &length);
    if (status != fmi2OK) return status;
    *size = STATE_HEADER + length;
    return fmi2OK;
}

static void put32(fmi2Byte *out, uint32_t v) { memcpy(out, &v, 4); }
static void put64(fmi2Byte *out, uint64_t v) { memcpy(out, &v, 8); }
static uint32_t get32(const fmi2Byte *in) { uint32_t v; memcpy(&v, in, 4); return v; }
static uint64_t get64(const fmi2Byte *in) { uint64_t v; memcpy(&v, in, 8); return v; }

/* The serialized form: magic, version, mode, payload length, GUID hash, then the slave's bytes. */
fmi2Status fmi2SerializeFMUstate(fmi2Component component, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size) {
    INSTANCE("fmi2SerializeFMUstate");
    State *state = as_state(FMUstate);
    if (state == NULL) return refuse(c, "fmi2SerializeFMUstate: not a state of this FMU");
    const char *data;
    size_t length;
    fmi2Status status = state_payload(c, "fmi2SerializeFMUstate", state, &data, &length);
    if (status != fmi2OK) return status;
    if (serializedState == NULL || size != STATE_HEADER + length)
        return refuse(c, "fmi2SerializeFMUstate: buffer of %zu bytes given, the state needs %zu",
                      size, STATE_HEADER + length);
    put32(serializedState, STATE_MAGIC);
    put32(serializedState + 4, STATE_VERSION);
    put32(serializedState + 8, (uint32_t)state->mode);
    put32(serializedState + 12, 0);
    put64(serializedState + 16, (uint64_t)length);
    put64(serializedState + 24, guid_hash(c->binding.guid));
    memcpy(serializedState + STATE_HEADER, data, length);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component component, const fmi2Byte serializedState[],
                                   size_t size, fmi2FMUstate *FMUstate) {
    INSTANCE("fmi2DeSerializeFMUstate");
    REQUIRE("fmi2DeSerializeFMUstate", M_ANY);
    if (FMUstate == NULL) return refuse(c, "fmi2DeSerializeFMUstate: FMUstate pointer is NULL");
    if (serializedState == NULL || size < STATE_HEADER)
        return refuse(c, "fmi2DeSerializeFMUstate: %zu bytes is too short for a state", size);
    uint32_t mode = get32(serializedState + 8);
    if (get32(serializedState) != STATE_MAGIC || get32(serializedState + 4) != STATE_VERSION)
        return refuse(c, "fmi2DeSerializeFMUstate: not a serialized state of a sonotrack FMU");
    if (get64(serializedState + 24) != guid_hash(c->binding.guid))
        return refuse(c, "fmi2DeSerializeFMUstate: the state was saved by another FMU (GUID "
                      "differs)");
    if (get64(serializedState + 16) != size - STATE_HEADER || mode == 0 || (mode & (mode - 1)) ||
        !(mode & M_ANY))
        return refuse(c, "fmi2DeSerializeFMUstate: corrupted state (length or mode field)");
    int gil = py.GILEnsure();
    PyObject *bytes = py.BytesFromStringAndSize((const char *)serializedState + STATE_HEADER,
                                                (Py_ssize_t_)(size - STATE_HEADER));
    PyObject *decoded = bytes ? py.CallArgs(c->from_bytes, bytes, NULL) : NULL;
    PyObject *data = decoded ? py.CallArgs(g_as_state, decoded, NULL) : NULL;
    if (decoded) py.DecRef(decoded);
    if (data == NULL) {
        if (bytes) py.DecRef(bytes);
        fmi2Status status = python_failure(c, "fmi2DeSerializeFMUstate", "corrupted state");
        py.GILRelease(gil);
        return status;
    }
    State *state = calloc(1, sizeof *state);
    if (state == NULL) {
        py.DecRef(bytes);
        py.DecRef(data);
        py.GILRelease(gil);
        return refuse(c, "fmi2DeSerializeFMUstate: out of memory");
    }
    state->magic = STATE_MAGIC;
    state->mode = (int)mode;
    state->data = data;
    state->bytes = bytes;
    py.GILRelease(gil);
    *FMUstate = state;
    return fmi2OK;
}
