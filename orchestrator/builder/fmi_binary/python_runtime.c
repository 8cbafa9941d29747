/* Finding or starting the Python interpreter, once per process, and its lifetime.
 *
 * The C-API functions are looked up with dlsym: in the host when it already runs Python, else in
 * the libpython the build recorded (or $SONOTRACK_LIBPYTHON), loaded with RTLD_GLOBAL. An
 * interpreter started here is never finalized (finalizing at unload or exit is what makes
 * pythonfmu's binary abort). The Python helpers below are pure Python, compiled once per process
 * into a private namespace that is kept for the process.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "sonotrack_fmi2.h"

#define PY_FILE_INPUT 257

PythonApi py;
pthread_mutex_t g_lock = PTHREAD_MUTEX_INITIALIZER;
int g_python_ready;
int g_fatal;
PyObject *g_load_class, *g_make, *g_drain, *g_classify, *g_as_state;

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
int start_python(const Binding *b, char *error, size_t size) {
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
