/* sonotrack's FMI 2.0 Co-Simulation binary (linux64) for FMUs whose model is a pythonfmu slave.
 *
 * One shared library serves every sonotrack FMU: what differs per FMU is read at fmi2Instantiate
 * from resources/sonotrack_binding.txt, written by `sonotrack build` (orchestrator/fmi_binary):
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
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <wchar.h>

#include "fmi2Functions.h"

/* ----- the part of the Python C API used here, resolved at run time ------------------------ */

typedef struct _object PyObject;
typedef long Py_ssize_t_;

#define PY_FILE_INPUT 257

static struct {
    int (*IsInitialized)(void);
    void (*InitializeEx)(int);
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
    void (*SetProgramName)(const wchar_t *);        /* optional: removed in Python 3.13 */
    wchar_t *(*DecodeLocale)(const char *, size_t *); /* optional */
    PyObject *None, *True, *False;
} py;

/* Python helpers (pure Python, run once per process in a private namespace). */
static const char BOOTSTRAP[] =
    "import importlib.util, os, sys, traceback\n"
    "def _load_file(name, path, package_dir=None):\n"
    "    locations = None if package_dir is None else [package_dir]\n"
    "    spec = importlib.util.spec_from_file_location(name, path,\n"
    "                                                  submodule_search_locations=locations)\n"
    "    if spec is None:\n"
    "        raise ImportError(f'cannot load {name} from {path}')\n"
    "    module = importlib.util.module_from_spec(spec)\n"
    "    sys.modules[name] = module\n"
    "    try:\n"
    "        spec.loader.exec_module(module)\n"
    "    except BaseException:\n"
    "        sys.modules.pop(name, None)\n"
    "        raise\n"
    "    return module\n"
    "def load_class(resources, package, entry, class_name):\n"
    "    try:\n"
    "        import pythonfmu\n"
    "    except ImportError:  # no pythonfmu in this Python: use the copy the FMU carries\n"
    "        bundled = os.path.join(resources, 'pythonfmu')\n"
    "        _load_file('pythonfmu', os.path.join(bundled, '__init__.py'), bundled)\n"
    "    package_dir = os.path.join(resources, package)\n"
    "    module = sys.modules.get(package)\n"
    "    if module is None:\n"
    "        _load_file(package, os.path.join(package_dir, '__init__.py'), package_dir)\n"
    "    elif not all(os.path.isdir(p) for p in module.__path__):\n"
    "        # the folder this build was first loaded from is gone; the name is the content's hash\n"
    "        module.__path__[:] = [package_dir]\n"
    "    entry_name = package + '._fmu_entry'\n"
    "    module = sys.modules.get(entry_name)\n"
    "    if module is None:\n"
    "        module = _load_file(entry_name, os.path.join(resources, entry + '.py'))\n"
    "    return getattr(module, class_name)\n"
    "def make(cls, instance_name, resources, visible):\n"
    "    slave = cls(instance_name=instance_name, resources=resources, visible=visible)\n"
    "    return (slave, slave.do_step, slave.log_queue, slave.setup_experiment,\n"
    "            slave.enter_initialization_mode, slave.exit_initialization_mode,\n"
    "            slave.terminate, slave._get_fmu_state, slave._set_fmu_state,\n"
    "            slave._fmu_state_to_bytes, slave._fmu_state_from_bytes)\n"
    "def drain(queue):\n"
    "    items = [(int(m.status), str(m.category or 'logAll'), str(m.msg)) for m in queue]\n"
    "    del queue[:]\n"
    "    return items\n"
    "def classify(exc, package):\n"
    "    errors = sys.modules.get(package + '.common.errors')\n"
    "    base = getattr(errors, 'SonotrackError', ())\n"
    "    rejected = getattr(errors, 'StepRejectedError', ())\n"
    "    if not isinstance(exc, Exception) or isinstance(exc, MemoryError):\n"
    "        return 4, f'{type(exc).__name__}: {exc}'\n"
    "    if rejected and isinstance(exc, rejected):\n"
    "        return 2, str(exc)\n"
    "    if base and isinstance(exc, base):\n"
    "        return 3, str(exc)\n"
    "    trace = ''.join(traceback.format_exception(exc)).rstrip()\n"
    "    return 3, f'unexpected {type(exc).__name__} in the model: {exc}\\n{trace}'\n"
    "def as_state(value):\n"
    "    if not isinstance(value, dict):\n"
    "        raise TypeError(f'a serialized state must decode to a dict, not {type(value).__name__}')\n"
    "    return value\n";

static pthread_mutex_t g_lock = PTHREAD_MUTEX_INITIALIZER;
static int g_python_ready;     /* symbols resolved, interpreter running, helpers compiled */
static int g_fatal;            /* the interpreter failed: every call returns fmi2Fatal */
static PyObject *g_load_class, *g_make, *g_drain, *g_classify, *g_as_state;

/* ----- the binding table ------------------------------------------------------------------ */

enum { T_NONE = 0, T_REAL, T_INTEGER, T_BOOLEAN, T_STRING };
enum { C_PARAMETER, C_CALCULATED, C_INPUT, C_OUTPUT, C_LOCAL, C_INDEPENDENT };
enum { V_CONSTANT, V_FIXED, V_TUNABLE, V_DISCRETE, V_CONTINUOUS };
enum { I_NONE, I_EXACT, I_APPROX, I_CALCULATED };

static const char *TYPE_NAMES[] = {"(none)", "Real", "Integer", "Boolean", "String"};
static const char *CAUSALITY_NAMES[] = {"parameter", "calculatedParameter", "input", "output",
                                        "local", "independent"};

typedef struct {
    int type, causality, variability, initial;
    char *name;
    PyObject *attribute; /* interned attribute name on the slave */
} Variable;

typedef struct {
    char *guid, *libpython, *python, *python_version, *package, *entry, *class_name;
    Variable *vars; /* indexed by value reference */
    size_t nvars;
} Binding;

/* ----- instances ------------------------------------------------------------------------- */

enum {
    M_INSTANTIATED = 1, M_INIT = 2, M_STEP_COMPLETE = 4, M_STEP_FAILED = 8, M_TERMINATED = 16,
    M_ERROR = 32
};
#define M_ANY (M_INSTANTIATED | M_INIT | M_STEP_COMPLETE | M_STEP_FAILED | M_TERMINATED | M_ERROR)
#define M_GET (M_INIT | M_STEP_COMPLETE | M_STEP_FAILED | M_TERMINATED | M_ERROR)
#define M_SET (M_INSTANTIATED | M_INIT | M_STEP_COMPLETE)

enum { CAT_WARNING = 1, CAT_DISCARD = 2, CAT_ERROR = 4, CAT_FATAL = 8, CAT_ALL = 16 };
static const char *CATEGORY_NAMES[] = {"logStatusWarning", "logStatusDiscard", "logStatusError",
                                       "logStatusFatal", "logAll"};

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

#define STATE_MAGIC 0x534b5453u /* "STKS" */
#define STATE_VERSION 1u
#define STATE_HEADER 32

typedef struct {
    uint32_t magic;
    int mode;
    PyObject *data;  /* the slave's state dict */
    PyObject *bytes; /* its serialized form, made on demand */
} State;

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

/* ----- logging ------------------------------------------------------------------------------ */

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
static void emit(fmi2CallbackLogger logger, fmi2ComponentEnvironment environment,
                 const char *instance, int logging_on, int categories, fmi2Status status,
                 const char *category, const char *message) {
    if (logger == NULL) return;
    if (status == fmi2OK && !(logging_on && (categories & CAT_ALL))) return;
    if (category == NULL) category = CATEGORY_NAMES[__builtin_ctz(category_of_status(status))];
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

static void logf_(Instance *c, fmi2Status status, const char *format, ...)
    __attribute__((format(printf, 3, 4)));

static void logf_(Instance *c, fmi2Status status, const char *format, ...) {
    char buffer[2048];
    va_list args;
    va_start(args, format);
    vsnprintf(buffer, sizeof buffer, format, args);
    va_end(args);
    emit(c->logger, c->environment, c->name, c->logging_on, c->categories, status, NULL, buffer);
}

/* An fmi2Error refusal: logged, and the instance enters the error state. */
static fmi2Status refuse(Instance *c, const char *format, ...) __attribute__((format(printf, 2, 3)));

static fmi2Status refuse(Instance *c, const char *format, ...) {
    char buffer[2048];
    va_list args;
    va_start(args, format);
    vsnprintf(buffer, sizeof buffer, format, args);
    va_end(args);
    emit(c->logger, c->environment, c->name, c->logging_on, c->categories, fmi2Error, NULL, buffer);
    c->mode = M_ERROR;
    return fmi2Error;
}

static fmi2Status wrong_state(Instance *c, const char *function, int allowed) {
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

/* ----- Python errors ------------------------------------------------------------------------ */

/* Forward the slave's queued log messages to the host (GIL held). */
static void drain_log(Instance *c) {
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
static void exception_text(char *out, size_t size) {
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
static fmi2Status python_failure(Instance *c, const char *function, const char *what) {
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
    if (status == fmi2Fatal) g_fatal = 1;
    return status;
}

/* ----- loading Python ----------------------------------------------------------------------- */

static int resolve(void *handle, void **slot, const char *name, int required, char *error,
                   size_t size) {
    *slot = dlsym(handle, name);
    if (*slot == NULL && required) {
        snprintf(error, size, "Python C-API symbol %s not found", name);
        return -1;
    }
    return 0;
}

static int file_exists(const char *path) {
    struct stat info;
    return path != NULL && path[0] != '\0' && stat(path, &info) == 0;
}

/* Find or start the interpreter and compile the helpers; once per process (lock held). */
static int start_python(const Binding *b, char *error, size_t size) {
    void *handle = RTLD_DEFAULT;
    int host_has_python = dlsym(RTLD_DEFAULT, "Py_IsInitialized") != NULL;
    const char *library = getenv("SONOTRACK_LIBPYTHON");
    if (library == NULL || library[0] == '\0') library = b->libpython;
    if (!host_has_python) {
        handle = dlopen(library, RTLD_NOW | RTLD_GLOBAL);
        if (handle == NULL) {
            snprintf(error, size, "the host runs no Python and libpython could not be loaded "
                     "from %.900s (%s): %s", library, library == b->libpython ?
                     "recorded at build; set SONOTRACK_LIBPYTHON" : "from SONOTRACK_LIBPYTHON",
                     dlerror());
            return -1;
        }
    }
#define R(field, name) if (resolve(handle, (void **)&py.field, name, 1, error, size)) return -1
    R(IsInitialized, "Py_IsInitialized"); R(InitializeEx, "Py_InitializeEx");
    R(EvalSaveThread, "PyEval_SaveThread"); R(GILEnsure, "PyGILState_Ensure");
    R(GILRelease, "PyGILState_Release"); R(IncRef, "Py_IncRef"); R(DecRef, "Py_DecRef");
    R(ErrOccurred, "PyErr_Occurred"); R(ErrFetch, "PyErr_Fetch");
    R(ErrNormalize, "PyErr_NormalizeException"); R(ErrClear, "PyErr_Clear");
    R(GetAttr, "PyObject_GetAttr"); R(SetAttr, "PyObject_SetAttr");
    R(GetAttrString, "PyObject_GetAttrString"); R(Str, "PyObject_Str"); R(Repr, "PyObject_Repr");
    R(IsTrue, "PyObject_IsTrue"); R(CallObject, "PyObject_CallObject");
    R(CallArgs, "PyObject_CallFunctionObjArgs"); R(UnicodeFromString, "PyUnicode_FromString");
    R(InternFromString, "PyUnicode_InternFromString"); R(UnicodeAsUTF8, "PyUnicode_AsUTF8");
    R(FloatFromDouble, "PyFloat_FromDouble"); R(FloatAsDouble, "PyFloat_AsDouble");
    R(LongAsLong, "PyLong_AsLong"); R(LongFromLong, "PyLong_FromLong");
    R(BoolFromLong, "PyBool_FromLong"); R(TupleGetItem, "PyTuple_GetItem");
    R(TupleSize, "PyTuple_Size"); R(ListSize, "PyList_Size"); R(ListGetItem, "PyList_GetItem");
    R(BytesFromStringAndSize, "PyBytes_FromStringAndSize");
    R(BytesAsStringAndSize, "PyBytes_AsStringAndSize"); R(DictNew, "PyDict_New");
    R(DictSetItemString, "PyDict_SetItemString"); R(DictGetItemString, "PyDict_GetItemString");
    R(ImportModule, "PyImport_ImportModule"); R(RunStringFlags, "PyRun_StringFlags");
    R(GetVersion, "Py_GetVersion");
    R(None, "_Py_NoneStruct"); R(True, "_Py_TrueStruct"); R(False, "_Py_FalseStruct");
#undef R
    resolve(handle, (void **)&py.SetProgramName, "Py_SetProgramName", 0, error, size);
    resolve(handle, (void **)&py.DecodeLocale, "Py_DecodeLocale", 0, error, size);

    if (!py.IsInitialized()) {
        /* A C host: start the interpreter as the build's Python (its venv gives numpy). It is
         * never finalized: finalizing at unload or exit is what makes pythonfmu's binary abort. */
        const char *python = getenv("SONOTRACK_PYTHON");
        const char *origin = "from SONOTRACK_PYTHON";
        if (python == NULL || python[0] == '\0') {
            python = b->python;
            origin = "recorded at build; set SONOTRACK_PYTHON to a Python with numpy";
        }
        if (!file_exists(python)) {
            snprintf(error, size, "Python executable %.900s (%s) does not exist; the FMU was "
                     "built with Python %s", python, origin, b->python_version);
            return -1;
        }
        if (py.SetProgramName != NULL && py.DecodeLocale != NULL) {
            wchar_t *program = py.DecodeLocale(python, NULL); /* kept: Python keeps the pointer */
            if (program != NULL) py.SetProgramName(program);
        }
        py.InitializeEx(0); /* 0: leave the host's signal handlers alone */
        py.EvalSaveThread();
    }
    int gil = py.GILEnsure();
    int ok = 0;
    PyObject *globals = py.DictNew();
    PyObject *builtins = py.ImportModule("builtins");
    if (globals && builtins && py.DictSetItemString(globals, "__builtins__", builtins) == 0) {
        PyObject *result = py.RunStringFlags(BOOTSTRAP, PY_FILE_INPUT, globals, globals, NULL);
        if (result != NULL) {
            py.DecRef(result);
            g_load_class = py.DictGetItemString(globals, "load_class");
            g_make = py.DictGetItemString(globals, "make");
            g_drain = py.DictGetItemString(globals, "drain");
            g_classify = py.DictGetItemString(globals, "classify");
            g_as_state = py.DictGetItemString(globals, "as_state");
            ok = g_load_class && g_make && g_drain && g_classify && g_as_state;
            globals = NULL; /* kept alive for the process: the helpers live in it */
        }
    }
    if (!ok) {
        char text[1024];
        exception_text(text, sizeof text);
        snprintf(error, size, "cannot set up the FMU's Python helpers: %s", text);
    }
    if (builtins) py.DecRef(builtins);
    if (globals) py.DecRef(globals);
    py.GILRelease(gil);
    return ok ? 0 : -1;
}

/* ----- the binding table ---------------------------------------------------------------------- */

static int lookup(const char *word, const char **names, int n) {
    for (int i = 0; i < n; i++)
        if (strcmp(word, names[i]) == 0) return i;
    return -1;
}

static void free_binding(Binding *b, int python_alive) {
    for (size_t i = 0; i < b->nvars; i++) {
        free(b->vars[i].name);
        if (b->vars[i].attribute && python_alive) py.DecRef(b->vars[i].attribute);
    }
    free(b->vars);
    free(b->guid); free(b->libpython); free(b->python); free(b->python_version);
    free(b->package); free(b->entry); free(b->class_name);
    memset(b, 0, sizeof *b);
}

static int read_binding(const char *path, Binding *b, char *error, size_t size) {
    static const char *types[] = {"(none)", "Real", "Integer", "Boolean", "String"};
    static const char *variabilities[] = {"constant", "fixed", "tunable", "discrete", "continuous"};
    static const char *initials[] = {"-", "exact", "approx", "calculated"};
    FILE *file = fopen(path, "r");
    if (file == NULL) {
        snprintf(error, size, "cannot open %.900s: %s (was this FMU built by sonotrack build?)", path,
                 strerror(errno));
        return -1;
    }
    char line[4096];
    int number = 0, failed = 0;
    while (!failed && fgets(line, sizeof line, file) != NULL) {
        number++;
        line[strcspn(line, "\r\n")] = '\0';
        if (line[0] == '#' || line[0] == '\0') continue;
        char *fields[8];
        int n = 0;
        for (char *cursor = line; n < 8;) {
            fields[n++] = cursor;
            char *tab = strchr(cursor, '\t');
            if (tab == NULL) break;
            *tab = '\0';
            cursor = tab + 1;
        }
        char **slot = NULL;
        if (n == 2 && strcmp(fields[0], "guid") == 0) slot = &b->guid;
        else if (n == 2 && strcmp(fields[0], "libpython") == 0) slot = &b->libpython;
        else if (n == 2 && strcmp(fields[0], "python") == 0) slot = &b->python;
        else if (n == 2 && strcmp(fields[0], "python_version") == 0) slot = &b->python_version;
        else if (n == 2 && strcmp(fields[0], "package") == 0) slot = &b->package;
        else if (n == 2 && strcmp(fields[0], "entry") == 0) slot = &b->entry;
        else if (n == 2 && strcmp(fields[0], "class") == 0) slot = &b->class_name;
        if (slot != NULL) {
            free(*slot);
            *slot = strdup(fields[1]);
            continue;
        }
        if (n == 7 && strcmp(fields[0], "var") == 0) {
            char *end;
            unsigned long vr = strtoul(fields[1], &end, 10);
            int type = lookup(fields[2], types, 5);
            int causality = lookup(fields[3], CAUSALITY_NAMES, 6);
            int variability = lookup(fields[4], variabilities, 5);
            int initial = lookup(fields[5], initials, 4);
            if (*end || vr > 1000000 || type <= 0 || causality < 0 || variability < 0 ||
                initial < 0) {
                failed = 1;
                break;
            }
            if (vr >= b->nvars) {
                Variable *grown = realloc(b->vars, (vr + 1) * sizeof *grown);
                if (grown == NULL) { failed = 1; break; }
                memset(grown + b->nvars, 0, (vr + 1 - b->nvars) * sizeof *grown);
                b->vars = grown;
                b->nvars = vr + 1;
            }
            Variable *v = &b->vars[vr];
            if (v->type != T_NONE) { failed = 1; break; }
            v->type = type; v->causality = causality; v->variability = variability;
            v->initial = initial; v->name = strdup(fields[6]);
            continue;
        }
        failed = 1;
    }
    fclose(file);
    if (failed) {
        snprintf(error, size, "%.900s line %d is malformed", path, number);
        return -1;
    }
    if (!b->guid || !b->libpython || !b->python || !b->python_version || !b->package ||
        !b->entry || !b->class_name) {
        snprintf(error, size, "%.900s lacks one of guid, libpython, python, python_version, package, "
                 "entry, class", path);
        return -1;
    }
    return 0;
}

/* file:///a%20b/resources -> /a b/resources (no trailing slash). */
static char *path_from_uri(const char *uri) {
    const char *p = uri;
    if (strncmp(p, "file://", 7) == 0) {
        p += 7;
        if (strncmp(p, "localhost/", 10) == 0) p += 9;
    } else if (strncmp(p, "file:", 5) == 0) {
        p += 5;
    }
    char *path = malloc(strlen(p) + 1), *out = path;
    if (path == NULL) return NULL;
    for (; *p; p++) {
        unsigned int code;
        if (p[0] == '%' && p[1] && p[2] && sscanf(p + 1, "%2x", &code) == 1) {
            *out++ = (char)code;
            p += 2;
        } else {
            *out++ = *p;
        }
    }
    *out = '\0';
    while (out > path + 1 && out[-1] == '/') *--out = '\0';
    return path;
}

/* <fmu>/binaries/linux64/<model>.so -> <fmu>/resources, for hosts that pass no location. */
static char *resources_beside_binary(void) {
    Dl_info info;
    if (!dladdr((void *)&resources_beside_binary, &info) || info.dli_fname == NULL) return NULL;
    char *path = malloc(strlen(info.dli_fname) + 16);
    if (path == NULL) return NULL;
    strcpy(path, info.dli_fname);
    for (int up = 0; up < 3; up++) {
        char *slash = strrchr(path, '/');
        if (slash == NULL) { free(path); return NULL; }
        *slash = '\0';
    }
    strcat(path, "/resources");
    return path;
}

/* ----- helpers for every call ----------------------------------------------------------------- */

#define INSTANCE(function)                                                                     \
    Instance *c = (Instance *)component;                                                       \
    if (c == NULL) return fmi2Error;                                                           \
    if (g_fatal) return fmi2Fatal;

#define REQUIRE(function, allowed)                                                             \
    if (!(c->mode & (allowed))) return wrong_state(c, function, allowed);                       \
    if (c->slave == NULL) return refuse(c, "%s: the model could not be re-created", function)

static void release_strings(Instance *c) {
    for (size_t i = 0; i < c->nstrings; i++)
        if (c->strings[i]) py.DecRef(c->strings[i]);
    free(c->strings);
    c->strings = NULL;
    c->nstrings = 0;
}

static void drop_slave(Instance *c) {
    PyObject **fields[] = {&c->slave, &c->do_step, &c->log_queue, &c->setup, &c->enter, &c->exit,
                           &c->terminate, &c->get_state, &c->set_state, &c->to_bytes,
                           &c->from_bytes};
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
    PyObject **fields[] = {&c->slave, &c->do_step, &c->log_queue, &c->setup, &c->enter, &c->exit,
                           &c->terminate, &c->get_state, &c->set_state, &c->to_bytes,
                           &c->from_bytes};
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
    char error[2048] = "";
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
    c->categories = CAT_WARNING | CAT_DISCARD | CAT_ERROR | CAT_FATAL | CAT_ALL;
    c->visible = visible ? 1 : 0;
    c->mode = M_INSTANTIATED;
    if (g_fatal) FAIL("fmi2Instantiate: the Python interpreter failed earlier in this process");
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
    pthread_mutex_lock(&g_lock);
    int started = g_python_ready || start_python(&c->binding, error + 17, sizeof error - 17) == 0;
    if (started) g_python_ready = 1;
    pthread_mutex_unlock(&g_lock);
    if (!started) {
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
        py.GILRelease(gil);
        goto failed;
    }
    py.GILRelease(gil);
    return c;
failed:
    emit(logger, environment, name, 1, CAT_ALL, fmi2Error, "logStatusError", error);
    if (c) free_instance(c, g_python_ready && !g_fatal);
    return NULL;
#undef FAIL
}

void fmi2FreeInstance(fmi2Component component) {
    Instance *c = (Instance *)component;
    if (c == NULL) return;
    if (g_fatal) { /* never touch a failed interpreter; the Python objects leak */
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
    c->categories = nCategories ? mask : (CAT_WARNING | CAT_DISCARD | CAT_ERROR | CAT_FATAL | CAT_ALL);
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

fmi2Status fmi2SetupExperiment(fmi2Component component, fmi2Boolean toleranceDefined,
                               fmi2Real tolerance, fmi2Real startTime,
                               fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    INSTANCE("fmi2SetupExperiment");
    REQUIRE("fmi2SetupExperiment", M_INSTANTIATED);
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
    int gil = py.GILEnsure();
    fmi2Status status = init_result(c, py.CallObject(c->enter, NULL),
                                    "fmi2EnterInitializationMode", "enter_initialization_mode");
    if (status == fmi2OK) c->mode = M_INIT;
    py.GILRelease(gil);
    return status;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component component) {
    INSTANCE("fmi2ExitInitializationMode");
    REQUIRE("fmi2ExitInitializationMode", M_INIT);
    int gil = py.GILEnsure();
    fmi2Status status = init_result(c, py.CallObject(c->exit, NULL),
                                    "fmi2ExitInitializationMode", "exit_initialization_mode");
    if (status == fmi2OK) c->mode = M_STEP_COMPLETE;
    py.GILRelease(gil);
    return status;
}

fmi2Status fmi2Terminate(fmi2Component component) {
    INSTANCE("fmi2Terminate");
    REQUIRE("fmi2Terminate", M_STEP_COMPLETE | M_STEP_FAILED);
    int gil = py.GILEnsure();
    fmi2Status status = init_result(c, py.CallObject(c->terminate, NULL), "fmi2Terminate",
                                    "terminate");
    if (status == fmi2OK) c->mode = M_TERMINATED;
    py.GILRelease(gil);
    return status;
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

/* ----- FMI 2.0: variables ------------------------------------------------------------------- */

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

static fmi2Status attribute_failure(Instance *c, const char *function, const Variable *v) {
    char what[512];
    snprintf(what, sizeof what, "variable %s", v->name);
    return python_failure(c, function, what);
}

#define GET_PROLOGUE(function, type)                                                           \
    INSTANCE(function);                                                                        \
    REQUIRE(function, M_GET);                                                                  \
    if (check_references(c, function, vr, nvr, type) != fmi2OK) return fmi2Error;             \
    if (nvr > 0 && value == NULL) return refuse(c, "%s: value array is NULL", function);       \
    int gil = py.GILEnsure();

fmi2Status fmi2GetReal(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[]) {
    GET_PROLOGUE("fmi2GetReal", T_REAL);
    for (size_t i = 0; i < nvr; i++) {
        const Variable *v = &c->binding.vars[vr[i]];
        PyObject *object = py.GetAttr(c->slave, v->attribute);
        double number = object ? py.FloatAsDouble(object) : -1.0;
        if (object) py.DecRef(object);
        if (number == -1.0 && py.ErrOccurred()) {
            fmi2Status status = attribute_failure(c, "fmi2GetReal", v);
            py.GILRelease(gil);
            return status;
        }
        value[i] = number;
    }
    py.GILRelease(gil);
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[]) {
    GET_PROLOGUE("fmi2GetInteger", T_INTEGER);
    for (size_t i = 0; i < nvr; i++) {
        const Variable *v = &c->binding.vars[vr[i]];
        PyObject *object = py.GetAttr(c->slave, v->attribute);
        long number = object ? py.LongAsLong(object) : -1;
        if (object) py.DecRef(object);
        if (number == -1 && py.ErrOccurred()) {
            fmi2Status status = attribute_failure(c, "fmi2GetInteger", v);
            py.GILRelease(gil);
            return status;
        }
        if (number < INT32_MIN || number > INT32_MAX) {
            py.GILRelease(gil);
            return refuse(c, "fmi2GetInteger: variable %s = %ld does not fit an fmi2Integer",
                          v->name, number);
        }
        value[i] = (fmi2Integer)number;
    }
    py.GILRelease(gil);
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[]) {
    GET_PROLOGUE("fmi2GetBoolean", T_BOOLEAN);
    for (size_t i = 0; i < nvr; i++) {
        const Variable *v = &c->binding.vars[vr[i]];
        PyObject *object = py.GetAttr(c->slave, v->attribute);
        int truth = object ? py.IsTrue(object) : -1;
        if (object) py.DecRef(object);
        if (truth < 0) {
            fmi2Status status = attribute_failure(c, "fmi2GetBoolean", v);
            py.GILRelease(gil);
            return status;
        }
        value[i] = truth ? fmi2True : fmi2False;
    }
    py.GILRelease(gil);
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[]) {
    GET_PROLOGUE("fmi2GetString", T_STRING);
    release_strings(c);
    c->strings = calloc(nvr ? nvr : 1, sizeof *c->strings);
    if (c->strings == NULL) {
        py.GILRelease(gil);
        return refuse(c, "fmi2GetString: out of memory");
    }
    c->nstrings = nvr;
    for (size_t i = 0; i < nvr; i++) {
        const Variable *v = &c->binding.vars[vr[i]];
        PyObject *object = py.GetAttr(c->slave, v->attribute);
        PyObject *text = object ? py.Str(object) : NULL;
        if (object) py.DecRef(object);
        const char *utf8 = text ? py.UnicodeAsUTF8(text) : NULL;
        if (utf8 == NULL) {
            if (text) py.DecRef(text);
            fmi2Status status = attribute_failure(c, "fmi2GetString", v);
            py.GILRelease(gil);
            return status;
        }
        c->strings[i] = text; /* utf8 lives as long as text */
        value[i] = utf8;
    }
    py.GILRelease(gil);
    return fmi2OK;
}

#define SET_PROLOGUE(function, type)                                                           \
    INSTANCE(function);                                                                        \
    REQUIRE(function, M_SET);                                                                  \
    if (check_references(c, function, vr, nvr, type) != fmi2OK) return fmi2Error;             \
    if (check_settable(c, function, vr, nvr) != fmi2OK) return fmi2Error;                     \
    if (nvr > 0 && value == NULL) return refuse(c, "%s: value array is NULL", function);       \
    int gil = py.GILEnsure();

#define SET_ONE(function, make)                                                                \
    const Variable *v = &c->binding.vars[vr[i]];                                               \
    PyObject *object = (make);                                                                 \
    int failed = object == NULL || py.SetAttr(c->slave, v->attribute, object) != 0;            \
    if (object) py.DecRef(object);                                                             \
    if (failed) {                                                                              \
        fmi2Status status = attribute_failure(c, function, v);                                 \
        py.GILRelease(gil);                                                                    \
        return status;                                                                         \
    }

fmi2Status fmi2SetReal(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[]) {
    SET_PROLOGUE("fmi2SetReal", T_REAL);
    for (size_t i = 0; i < nvr; i++) {
        SET_ONE("fmi2SetReal", py.FloatFromDouble(value[i]));
    }
    py.GILRelease(gil);
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[]) {
    SET_PROLOGUE("fmi2SetInteger", T_INTEGER);
    for (size_t i = 0; i < nvr; i++) {
        SET_ONE("fmi2SetInteger", py.LongFromLong(value[i]));
    }
    py.GILRelease(gil);
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[]) {
    SET_PROLOGUE("fmi2SetBoolean", T_BOOLEAN);
    for (size_t i = 0; i < nvr; i++) {
        SET_ONE("fmi2SetBoolean", py.BoolFromLong(value[i] != fmi2False));
    }
    py.GILRelease(gil);
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component component, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[]) {
    SET_PROLOGUE("fmi2SetString", T_STRING);
    for (size_t i = 0; i < nvr; i++) {
        if (value[i] == NULL) {
            py.GILRelease(gil);
            return refuse(c, "fmi2SetString: NULL string for variable %s",
                          c->binding.vars[vr[i]].name);
        }
    }
    for (size_t i = 0; i < nvr; i++) {
        SET_ONE("fmi2SetString", py.UnicodeFromString(value[i]));
    }
    py.GILRelease(gil);
    return fmi2OK;
}

/* ----- FMI 2.0: stepping -------------------------------------------------------------------- */

fmi2Status fmi2DoStep(fmi2Component component, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    INSTANCE("fmi2DoStep");
    REQUIRE("fmi2DoStep", M_STEP_COMPLETE);
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

/* ----- FMI 2.0: FMU state ------------------------------------------------------------------- */

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

/* The serialized form: magic, version, mode, payload length, GUID hash, then the slave's bytes. */
static fmi2Status state_bytes(Instance *c, const char *function, State *state) {
    if (state->bytes != NULL) return fmi2OK;
    int gil = py.GILEnsure();
    state->bytes = py.CallArgs(c->to_bytes, state->data, NULL);
    fmi2Status status = fmi2OK;
    if (state->bytes == NULL) status = python_failure(c, function, "_fmu_state_to_bytes");
    py.GILRelease(gil);
    return status;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component component, fmi2FMUstate FMUstate,
                                      size_t *size) {
    INSTANCE("fmi2SerializedFMUstateSize");
    State *state = as_state(FMUstate);
    if (state == NULL || size == NULL)
        return refuse(c, "fmi2SerializedFMUstateSize: not a state of this FMU");
    fmi2Status status = state_bytes(c, "fmi2SerializedFMUstateSize", state);
    if (status != fmi2OK) return status;
    char *data;
    Py_ssize_t_ length;
    int gil = py.GILEnsure();
    py.BytesAsStringAndSize(state->bytes, &data, &length);
    py.GILRelease(gil);
    *size = STATE_HEADER + (size_t)length;
    return fmi2OK;
}

static void put32(fmi2Byte *out, uint32_t v) { memcpy(out, &v, 4); }
static void put64(fmi2Byte *out, uint64_t v) { memcpy(out, &v, 8); }
static uint32_t get32(const fmi2Byte *in) { uint32_t v; memcpy(&v, in, 4); return v; }
static uint64_t get64(const fmi2Byte *in) { uint64_t v; memcpy(&v, in, 8); return v; }

fmi2Status fmi2SerializeFMUstate(fmi2Component component, fmi2FMUstate FMUstate,
                                 fmi2Byte serializedState[], size_t size) {
    INSTANCE("fmi2SerializeFMUstate");
    State *state = as_state(FMUstate);
    if (state == NULL) return refuse(c, "fmi2SerializeFMUstate: not a state of this FMU");
    fmi2Status status = state_bytes(c, "fmi2SerializeFMUstate", state);
    if (status != fmi2OK) return status;
    char *data;
    Py_ssize_t_ length;
    int gil = py.GILEnsure();
    py.BytesAsStringAndSize(state->bytes, &data, &length);
    if (serializedState == NULL || size != STATE_HEADER + (size_t)length) {
        py.GILRelease(gil);
        return refuse(c, "fmi2SerializeFMUstate: buffer of %zu bytes given, the state needs %zu",
                      size, STATE_HEADER + (size_t)length);
    }
    put32(serializedState, STATE_MAGIC);
    put32(serializedState + 4, STATE_VERSION);
    put32(serializedState + 8, (uint32_t)state->mode);
    put32(serializedState + 12, 0);
    put64(serializedState + 16, (uint64_t)length);
    put64(serializedState + 24, guid_hash(c->binding.guid));
    memcpy(serializedState + STATE_HEADER, data, (size_t)length);
    py.GILRelease(gil);
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
