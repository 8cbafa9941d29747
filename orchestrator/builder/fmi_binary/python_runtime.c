/* Finding or starting the Python interpreter, once per process, and its lifetime.
 *
 * The C-API functions are looked up with dlsym: in the host when it already runs Python, else in
 * the libpython the build recorded (or $SONOTRACK_LIBPYTHON), loaded with RTLD_GLOBAL. An
 * interpreter started here is never finalized (finalizing at unload or exit is what makes
 * pythonfmu's binary abort). The Python helpers below are pure Python, compiled once per copy of
 * this library into a private namespace that is kept for the process.
 *
 * Threads: starting is done once per copy of the library under the process-wide mutex
 * (process_lock.c), so two copies never start two interpreters, and a thread that holds the GIL
 * never waits for that mutex (it lets the GIL go first: the thread holding the mutex may need
 * it). Loading a build's code takes a lock kept in sys.modules, shared by every copy, and
 * Python's lock waits release the GIL.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sonotrack_fmi2.h"

#define PY_FILE_INPUT 257

PythonApi py;
static int python_ready; /* this copy: symbols resolved, helpers compiled (atomic) */
int g_fatal;
PyObject *g_load_class, *g_make, *g_drain, *g_classify, *g_as_state;

/* Python helpers (pure Python, run once per process in a private namespace). */
static const char BOOTSTRAP[] =
    "import importlib.util, os, sys, threading, traceback, types\n"
    "# one lock for loading build code, shared by every copy of the library in the process\n"
    "_shared = sys.modules.get('_sonotrack_fmi2_runtime')\n"
    "if _shared is None:\n"
    "    _new = types.ModuleType('_sonotrack_fmi2_runtime')\n"
    "    _new.load_lock = threading.RLock()\n"
    "    _shared = sys.modules.setdefault('_sonotrack_fmi2_runtime', _new)\n"
    "_load_lock = _shared.load_lock\n"
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
    "    # a module is in sys.modules before it has run: without the lock another thread\n"
    "    # would take a half-loaded build\n"
    "    with _load_lock:\n"
    "        return _load_class(resources, package, entry, class_name)\n"
    "def _add_runtime(resources):\n"
    "    # An interpreter started from a portable FMU's runtime (its prefix holds the manifest)\n"
    "    # has the modules that FMU carries only, numpy perhaps not: a later FMU that carries a\n"
    "    # runtime of its own adds that runtime's folders at the end of the path, once.\n"
    "    if not os.path.isfile(os.path.join(sys.prefix, 'sonotrack_runtime.json')):\n"
    "        return\n"
    "    root = os.path.dirname(os.path.normpath(resources))\n"
    "    runtime = os.path.join(root, 'binaries', 'linux64', 'python')\n"
    "    if not os.path.isfile(os.path.join(runtime, 'sonotrack_runtime.json')) or \\\n"
    "            os.path.realpath(runtime) == os.path.realpath(sys.prefix):\n"
    "        return\n"
    "    lib = os.path.join(runtime, 'lib', 'python%d.%d' % sys.version_info[:2])\n"
    "    for name in ('', 'lib-dynload', 'site-packages'):\n"
    "        folder = os.path.join(lib, name) if name else lib\n"
    "        if os.path.isdir(folder) and folder not in sys.path:\n"
    "            sys.path.append(folder)\n"
    "def _load_class(resources, package, entry, class_name):\n"
    "    _add_runtime(resources)\n"
    "    # the build's code, its private pythonfmu (package._pythonfmu) included\n"
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

static int resolve(void *handle, void **slot, const char *name, int required, char *error,
                   size_t size) {
    *slot = dlsym(handle, name);
    if (*slot == NULL && required) {
        snprintf(error, size, "Python C-API symbol %s not found", name);
        return -1;
    }
    return 0;
}

/* PyStatus, as Py_InitializeFromConfig returns it (the same layout in 3.8 to 3.13). */
typedef struct {
    int type; /* 0 ok, 1 error, 2 exit */
    const char *func, *err_msg;
    int exitcode;
} PyStatus_;

/* Start the chosen Python: its libpython is loaded privately first and its version read, then
 * made global (extension modules such as numpy's resolve the C API from the global scope). The
 * interpreter is started from an isolated configuration: it leaves the host's locale, signal
 * handlers and environment alone (no PYTHONPATH or PYTHONHOME can pair it with another
 * installation), and a failure is a status returned to us, never an exit of the host. It is
 * never finalized: finalizing at unload or exit is what makes pythonfmu's binary abort. */
static void *load_chosen(const PythonChoice *choice, char *error, size_t size) {
    void *handle = dlopen(choice->libpython, RTLD_NOW | RTLD_LOCAL);
    if (handle == NULL) {
        snprintf(error, size, "libpython %.1000s (%s) could not be loaded: %s", choice->libpython,
                 choice->origin, dlerror());
        return NULL;
    }
    const char *(*version)(void);
    *(void **)&version = dlsym(handle, "Py_GetVersion");
    char expected[16];
    snprintf(expected, sizeof expected, "3.%d.", choice->minor);
    if (version == NULL || strncmp(version(), expected, strlen(expected)) != 0) {
        snprintf(error, size, "libpython %.1000s (%s) is not Python 3.%d as its name says (%.20s)",
                 choice->libpython, choice->origin, choice->minor, version ? version() : "?");
        dlclose(handle);
        return NULL;
    }
    return dlopen(choice->libpython, RTLD_NOW | RTLD_NOLOAD | RTLD_GLOBAL);
}

static int start_interpreter(void *handle, const PythonChoice *choice, char *error,
                             size_t size) {
    void (*init_config)(void *), (*clear_config)(void *);
    PyStatus_ (*set_argv)(void *, Py_ssize_t_, char *const *);
    PyStatus_ (*initialize)(const void *);
    *(void **)&init_config = dlsym(handle, "PyConfig_InitIsolatedConfig");
    *(void **)&clear_config = dlsym(handle, "PyConfig_Clear");
    *(void **)&set_argv = dlsym(handle, "PyConfig_SetBytesArgv");
    *(void **)&initialize = dlsym(handle, "Py_InitializeFromConfig");
    void *config = calloc(1, 16384); /* sizeof(PyConfig) is about 500 bytes in 3.11 to 3.13 */
    if (!init_config || !clear_config || !set_argv || !initialize || !config) {
        free(config);
        snprintf(error, size, "libpython %.1000s lacks the PyConfig API", choice->libpython);
        return -1;
    }
    init_config(config);
    /* argv[0] is the program Python locates its installation (a venv's pyvenv.cfg) from */
    char *argv[] = {(char *)(uintptr_t)choice->program, NULL};
    PyStatus_ status = set_argv(config, 1, argv);
    if (status.type == 0) status = initialize(config);
    clear_config(config);
    free(config);
    if (status.type != 0) {
        snprintf(error, size, "Python 3.%d from %.1000s (%s) failed to start: %s: %s",
                 choice->minor, choice->program, choice->origin, status.func ? status.func : "?",
                 status.err_msg ? status.err_msg : "exit requested");
        return -1;
    }
    py.EvalSaveThread(); /* the GIL is taken per call from now on */
    return 0;
}

/* Find or start the interpreter and compile the helpers; once per copy (process lock held). */
static int start_python(const Binding *b, char *error, size_t size) {
    void *handle = RTLD_DEFAULT;
    int (*initialized)(void);
    *(void **)&initialized = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    int running = initialized != NULL && initialized();
    char *failure = sonotrack_fmi2_start_failure_v1();
    PythonChoice *choice = NULL;
    if (!running) {
        if (failure[0]) { /* a start failed earlier: the interpreter cannot be started again */
            snprintf(error, size, "%s", failure);
            return -1;
        }
        Dl_info loaded = {0};
        if (initialized != NULL) dladdr(*(void **)&initialized, &loaded);
        choice = calloc(1, sizeof *choice);
        if (choice == NULL || find_python(b, loaded.dli_fname, choice, error, size) != 0 ||
            (handle = load_chosen(choice, error, size)) == NULL) {
            if (choice == NULL) snprintf(error, size, "out of memory");
            free(choice);
            return -1;
        }
    }
#define R(field, name)                                                                         \
    if (resolve(handle, (void **)&py.field, name, 1, error, size)) {                           \
        free(choice);                                                                          \
        return -1;                                                                             \
    }
    R(IsInitialized, "Py_IsInitialized");
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
    if (!running) {
        int started = start_interpreter(handle, choice, error, size) == 0;
        free(choice);
        if (!started) { /* every later instantiation, in any copy, gives the same reason */
            snprintf(failure, START_FAILURE_SIZE, "%s", error);
            return -1;
        }
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

/* Take the process-wide mutex without holding the GIL: a thread that holds it (a Python host
 * calling through ctypes.PyDLL) lets it go while waiting, since the holder of the mutex may be
 * waiting for the GIL. This thread holds the GIL when the thread state attached to the GIL is
 * its own (PyGILState_Check is not used: it answers 1 for every thread once a subinterpreter
 * exists). */
static void lock_process(pthread_mutex_t *lock) {
    if (pthread_mutex_trylock(lock) == 0) return;
    int (*initialized)(void);
    void *(*attached)(void), *(*own)(void), *(*save)(void);
    void (*restore)(void *);
    *(void **)&initialized = dlsym(RTLD_DEFAULT, "Py_IsInitialized");
    *(void **)&attached = dlsym(RTLD_DEFAULT, "PyThreadState_GetUnchecked"); /* 3.13 */
    if (attached == NULL) *(void **)&attached = dlsym(RTLD_DEFAULT, "_PyThreadState_UncheckedGet");
    *(void **)&own = dlsym(RTLD_DEFAULT, "PyGILState_GetThisThreadState");
    *(void **)&save = dlsym(RTLD_DEFAULT, "PyEval_SaveThread");
    *(void **)&restore = dlsym(RTLD_DEFAULT, "PyEval_RestoreThread");
    if (initialized && attached && own && save && restore && initialized()) {
        void *mine = own();
        if (mine != NULL && attached() == mine) {
            void *state = save();
            pthread_mutex_lock(lock);
            restore(state);
            return;
        }
    }
    pthread_mutex_lock(lock);
}

int ensure_python(const Binding *b, char *error, size_t size) {
    if (__atomic_load_n(&python_ready, __ATOMIC_ACQUIRE)) return 0;
    pthread_mutex_t *lock = sonotrack_fmi2_process_lock_v1();
    lock_process(lock);
    int status = 0;
    if (!__atomic_load_n(&python_ready, __ATOMIC_ACQUIRE)) {
        status = start_python(b, error, size);
        if (status == 0) __atomic_store_n(&python_ready, 1, __ATOMIC_RELEASE);
    }
    pthread_mutex_unlock(lock);
    return status;
}
