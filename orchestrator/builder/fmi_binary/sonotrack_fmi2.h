/* sonotrack's FMI 2.0 Co-Simulation binary (linux64): what its source files share (private).
 *
 * One shared library serves every sonotrack FMU: what differs per FMU is read at fmi2Instantiate
 * from resources/sonotrack_binding.txt, written by `sonotrack build` (orchestrator/builder/fmi_binary):
 * the GUID, the private package and entry module of the slave, the build-time libpython and
 * Python executable, and one line per variable (value reference, type, causality, variability).
 *
 * Design (docs/fmi_binary.md says why):
 * - No link-time dependency on libpython: every Python C-API function is looked up with dlsym,
 *   first in the host (fmpy, libcosimpy already run Python) and otherwise in the libpython the
 *   build recorded (or $SONOTRACK_LIBPYTHON), loaded with RTLD_GLOBAL. So the library loads in
 *   any host, with or without LD_PRELOAD.
 * - The interpreter is never finalized, and the library has no constructors, destructors or
 *   static objects with destructors: nothing runs at dlclose or at process exit.
 * - Python objects created here are pure Python (no C callbacks into this library), so nothing
 *   dangles after dlclose.
 * - Per call: value references are checked against the table in C, ports are read and written
 *   as attributes of the slave by interned name, do_step is a cached bound method, and log
 *   messages are only looked at when the slave queued some.
 *
 * The sources, one concept each (all compiled into one library by `make`; everything but the
 * fmi2 functions has hidden visibility):
 *   python_runtime.c  finding or starting the interpreter, the C-API table, the Python helpers
 *   binding.c         reading resources/sonotrack_binding.txt and the resource location
 *   status.c          logging to the host and mapping Python exceptions to FMI statuses
 *   instance.c        instances and the FMI 2.0 state machine (instantiate .. terminate, reset)
 *   variables.c       typed fmi2Get and fmi2Set with the variability rules
 *   step.c            fmi2DoStep and the calls this FMU does not support
 *   fmu_state.c       fmi2Get/Set/Free/Serialize/DeSerialize FMUstate
 */
#ifndef SONOTRACK_FMI2_H
#define SONOTRACK_FMI2_H

#include <pthread.h>
#include <stddef.h>
#include <stdint.h>

#include "fmi2Functions.h"

/* ----- the part of the Python C API used here, resolved at run time (python_runtime.c) ----- */

typedef struct _object PyObject;
typedef long Py_ssize_t_;

typedef struct {
    int (*IsInitialized)(void);
    void *(*EvalSaveThread)(void);
    int (*GILEnsure)(void);
    void (*GILRelease)(int);
    void (*IncRef)(PyObject *);
    void (*DecRef)(PyObject *);
    PyObject *(*ErrOccurred)(void);
    void (*ErrFetch)(PyObject **, PyObject **, PyObject **);
    void (*ErrNormalize)(PyObject **, PyObject **, PyObject **);
    void (*ErrClear)(void);
    PyObject *(*GetAttr)(PyObject *, PyObject *);
    int (*SetAttr)(PyObject *, PyObject *, PyObject *);
    PyObject *(*GetAttrString)(PyObject *, const char *);
    PyObject *(*Str)(PyObject *);
    PyObject *(*Repr)(PyObject *);
    int (*IsTrue)(PyObject *);
    PyObject *(*CallObject)(PyObject *, PyObject *);
    PyObject *(*CallArgs)(PyObject *, ...); /* PyObject_CallFunctionObjArgs */
    PyObject *(*UnicodeFromString)(const char *);
    PyObject *(*InternFromString)(const char *);
    const char *(*UnicodeAsUTF8)(PyObject *);
    PyObject *(*FloatFromDouble)(double);
    double (*FloatAsDouble)(PyObject *);
    long (*LongAsLong)(PyObject *);
    PyObject *(*LongFromLong)(long);
    PyObject *(*BoolFromLong)(long);
    PyObject *(*TupleGetItem)(PyObject *, Py_ssize_t_);
    Py_ssize_t_ (*TupleSize)(PyObject *);
    Py_ssize_t_ (*ListSize)(PyObject *);
    PyObject *(*ListGetItem)(PyObject *, Py_ssize_t_);
    PyObject *(*BytesFromStringAndSize)(const char *, Py_ssize_t_);
    int (*BytesAsStringAndSize)(PyObject *, char **, Py_ssize_t_ *);
    PyObject *(*DictNew)(void);
    int (*DictSetItemString)(PyObject *, const char *, PyObject *);
    PyObject *(*DictGetItemString)(PyObject *, const char *);
    PyObject *(*ImportModule)(const char *);
    PyObject *(*RunStringFlags)(const char *, int, PyObject *, PyObject *, void *);
    const char *(*GetVersion)(void);
    PyObject *None, *True, *False;
} PythonApi;

extern PythonApi py;

/* What every copy of this library in a process shares (process_lock.c, built as
 * libsonotrack_fmi2_lock.so.1, exported from that library only): the one mutex of the process,
 * and why starting Python failed, if it did ("" otherwise; read and written under the mutex;
 * START_FAILURE_SIZE bytes), since an interpreter whose start failed cannot be started again. */
#define START_FAILURE_SIZE 4096
__attribute__((visibility("default"))) pthread_mutex_t *sonotrack_fmi2_process_lock_v1(void);
__attribute__((visibility("default"))) char *sonotrack_fmi2_start_failure_v1(void);

/* The Python side of this copy of the library (python_runtime.c). g_fatal is read without the
 * GIL by every call, so it is accessed atomically (FATAL/SET_FATAL). */
extern int g_fatal;            /* the interpreter failed: every call returns fmi2Fatal */
extern PyObject *g_load_class, *g_make, *g_drain, *g_classify, *g_as_state;
#define FATAL() __atomic_load_n(&g_fatal, __ATOMIC_RELAXED)
#define SET_FATAL() __atomic_store_n(&g_fatal, 1, __ATOMIC_RELAXED)

/* ----- the binding table (binding.c) ----------------------------------------------------- */

enum { T_NONE = 0, T_REAL, T_INTEGER, T_BOOLEAN, T_STRING };
enum { C_PARAMETER, C_CALCULATED, C_INPUT, C_OUTPUT, C_LOCAL, C_INDEPENDENT };
enum { V_CONSTANT, V_FIXED, V_TUNABLE, V_DISCRETE, V_CONTINUOUS };
enum { I_NONE, I_EXACT, I_APPROX, I_CALCULATED };

extern const char *const TYPE_NAMES[5];

typedef struct {
    int type, causality, variability, initial;
    char *name;
    PyObject *attribute; /* interned attribute name on the slave */
} Variable;

typedef struct {
    char *guid, *libpython, *python, *python_version, *package, *entry, *class_name;
    char *runtime; /* absolute folder of the Python runtime a portable FMU carries, or NULL */
    int runtime_without_numpy; /* that runtime carries no numpy: the model needs none */
    Variable *vars; /* indexed by value reference */
    size_t nvars;
} Binding;

/* ----- instances and the FMI 2.0 state machine (instance.c) ------------------------------ */

enum {
    M_INSTANTIATED = 1, M_INIT = 2, M_STEP_COMPLETE = 4, M_STEP_FAILED = 8, M_TERMINATED = 16,
    M_ERROR = 32
};
#define M_ANY (M_INSTANTIATED | M_INIT | M_STEP_COMPLETE | M_STEP_FAILED | M_TERMINATED | M_ERROR)
#define M_GET (M_INIT | M_STEP_COMPLETE | M_STEP_FAILED | M_TERMINATED | M_ERROR)
#define M_SET (M_INSTANTIATED | M_INIT | M_STEP_COMPLETE)

enum { CAT_WARNING = 1, CAT_DISCARD = 2, CAT_ERROR = 4, CAT_FATAL = 8, CAT_ALL = 16 };
#define CAT_EVERY (CAT_WARNING | CAT_DISCARD | CAT_ERROR | CAT_FATAL | CAT_ALL)
extern const char *const CATEGORY_NAMES[5];

typedef struct {
    char *name, *resources;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    int logging_on, categories, visible, setup_done;
    int mode;
    Binding binding;
    PyObject *cls, *slave, *do_step, *log_queue, *setup, *enter, *exit, *terminate, *get_state,
        *set_state, *to_bytes, *from_bytes;
    PyObject **strings; /* keeps fmi2GetString's results alive until the next call */
    size_t nstrings;
} Instance;

/* Every fmi2 function taking a component starts with these. */
#define INSTANCE(function)                                                                     \
    Instance *c = (Instance *)component;                                                       \
    if (c == NULL) return fmi2Error;                                                           \
    if (FATAL()) return fmi2Fatal;

#define REQUIRE(function, allowed)                                                             \
    if (!(c->mode & (allowed))) return wrong_state(c, function, allowed);                       \
    if (c->slave == NULL) return refuse(c, "%s: the model could not be re-created", function)

/* python_runtime.c: 0 once this copy of the library can call Python (any thread, any time) */
int ensure_python(const Binding *b, char *error, size_t size);

/* python_search.c: the Python to start in a host that runs none. */
typedef struct {
    char libpython[4096], program[4096], origin[64]; /* program: argv[0] of the interpreter */
    int minor;                                       /* Python 3.minor */
} PythonChoice;
int find_python(const Binding *b, const char *loaded, PythonChoice *choice, char *error,
                size_t size);

/* binding.c */
int lookup(const char *word, const char *const *names, int n);
int read_binding(const char *path, Binding *b, char *error, size_t size);
void free_binding(Binding *b, int python_alive);
char *path_from_uri(const char *uri);
char *resources_beside_binary(void);

/* status.c: logging and status mapping */
void emit(fmi2CallbackLogger logger, fmi2ComponentEnvironment environment, const char *instance,
          int logging_on, int categories, fmi2Status status, const char *category,
          const char *message);
void logf_(Instance *c, fmi2Status status, const char *format, ...)
    __attribute__((format(printf, 3, 4)));
fmi2Status refuse(Instance *c, const char *format, ...) __attribute__((format(printf, 2, 3)));
void drain_log(Instance *c);
void exception_text(char *out, size_t size);
fmi2Status python_failure(Instance *c, const char *function, const char *what);

/* instance.c */
fmi2Status wrong_state(Instance *c, const char *function, int allowed);
void release_strings(Instance *c);

#endif
