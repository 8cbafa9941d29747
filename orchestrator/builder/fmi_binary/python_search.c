/* Finding a Python to start, for a host that runs none, in the order docs/fmi_binary.md documents:
 *
 *   1. SONOTRACK_PYTHON and/or SONOTRACK_LIBPYTHON (when either is set, only they are tried:
 *      an explicit choice is never passed over); libpython is derived from SONOTRACK_PYTHON
 *      when only that is set;
 *   2. the runtime a portable FMU carries (the binding table's runtime folder: its libpython,
 *      standard library and numpy, checked like any installation; numpy not when the table
 *      says the runtime carries none, runtime_numpy no: that model does not import it);
 *   3. the Python and libpython recorded at build (resources/sonotrack_binding.txt);
 *   4. python3.<build minor> and python3 on PATH (every match, in PATH order);
 *   5. the standard libpython locations (/usr/lib/x86_64-linux-gnu, /usr/lib64, /usr/local/lib,
 *      /usr/lib), for the build's minor version and the three after it.
 *
 * A candidate is checked from its files, before anything is loaded: the libpython exists and
 * its version (from its name) is the Python's and at least the build's, the installation it
 * belongs to (its prefix) is the Python's, the standard library is there (os.py, encodings,
 * lib-dynload: without them Python ends the process during start), and numpy is there with an
 * extension module built for that version. The first candidate that passes is used; if none
 * does, the caller gets one line naming every place tried, why each failed, and the fix.
 * Pure C, no Python: nothing here can end the host.
 */
#define _GNU_SOURCE
#include <dirent.h>
#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sonotrack_fmi2.h"

#define LATER_MINORS 3 /* besides the build's minor version, this many newer ones are accepted */

static const char *const STANDARD_DIRS[] = {"/usr/lib/x86_64-linux-gnu", "/usr/lib64",
                                            "/usr/local/lib", "/usr/lib"};

typedef struct {
    char *text;  /* the places tried, "; " separated */
    size_t size, used;
    int build_minor;
    int without_numpy; /* the candidate being judged need not have numpy */
    char seen[16][PATH_MAX]; /* environments already judged (one environment, one line) */
    int nseen;
} Search;

static void note(Search *s, const char *format, ...) __attribute__((format(printf, 2, 3)));

static void note(Search *s, const char *format, ...) {
    if (s->used + 3 >= s->size) return;
    if (s->used > 0) s->used += (size_t)snprintf(s->text + s->used, s->size - s->used, "; ");
    va_list args;
    va_start(args, format);
    int n = vsnprintf(s->text + s->used, s->size - s->used, format, args);
    va_end(args);
    if (n > 0) s->used += (size_t)n < s->size - s->used ? (size_t)n : s->size - s->used - 1;
}

static int exists(const char *path) { return path[0] != '\0' && access(path, F_OK) == 0; }

/* Format a path into a PATH_MAX buffer; a path that does not fit is "" (and so never exists). */
static void pathf(char *out, const char *format, ...) __attribute__((format(printf, 2, 3)));

static void pathf(char *out, const char *format, ...) {
    va_list args;
    va_start(args, format);
    int n = vsnprintf(out, PATH_MAX, format, args);
    va_end(args);
    if (n < 0 || n >= PATH_MAX) out[0] = '\0';
}

static void join(char *out, const char *a, const char *b) { pathf(out, "%s/%s", a, b); }

static void parent(char *path) { /* in place: /a/b/c -> /a/b; /a -> / */
    char *slash = strrchr(path, '/');
    if (slash == NULL) path[0] = '\0';
    else if (slash == path) path[1] = '\0';
    else *slash = '\0';
}

/* 3.<minor> from a name like python3.11, libpython3.11.so.1.0 (after the given stem); -1. */
static int minor_in_name(const char *path, const char *stem) {
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    size_t n = strlen(stem);
    if (strncmp(base, stem, n) != 0 || strncmp(base + n, "3.", 2) != 0) return -1;
    char *end;
    long minor = strtol(base + n + 2, &end, 10);
    return end == base + n + 2 || minor < 0 || minor > 99 ? -1 : (int)minor;
}

/* <folder>/<module>.py or, sourceless, .pyc (a runtime carried in an FMU). */
static int exists_py(const char *folder, const char *module) {
    char path[PATH_MAX];
    pathf(path, "%s/%s.py", folder, module);
    if (exists(path)) return 1;
    pathf(path, "%s/%s.pyc", folder, module);
    return exists(path);
}

/* The standard library of Python 3.<minor> under prefix: os.py, encodings, lib-dynload. */
static int has_stdlib(const char *prefix, int minor) {
    static const char *const libs[] = {"lib", "lib64"};
    for (size_t i = 0; i < 2; i++) {
        char base[PATH_MAX], path[PATH_MAX];
        pathf(base, "%s/%s/python3.%d", prefix, libs[i], minor);
        if (!exists_py(base, "os")) continue;
        if (!exists_py(base, "encodings/__init__")) continue;
        join(path, base, "lib-dynload");
        if (exists(path)) return 1;
    }
    return 0;
}

/* numpy with an extension module for CPython 3.<minor> in one site directory: 1 found,
 * 0 absent, -1 present but built for another Python. */
static int numpy_in(const char *site, int minor) {
    char path[PATH_MAX], tag[64];
    pathf(path, "%s/numpy", site);
    if (!exists_py(path, "__init__")) return 0;
    snprintf(tag, sizeof tag, "_multiarray_umath.cpython-3%d", minor);
    static const char *const cores[] = {"numpy/_core", "numpy/core"}; /* numpy 2, numpy 1 */
    for (size_t i = 0; i < 2; i++) {
        join(path, site, cores[i]);
        DIR *dir = opendir(path);
        if (dir == NULL) continue;
        int found = 0;
        for (struct dirent *e; !found && (e = readdir(dir)) != NULL;)
            found = strncmp(e->d_name, tag, strlen(tag)) == 0 && strstr(e->d_name, ".so") != NULL;
        closedir(dir);
        if (found) return 1;
    }
    return -1;
}

/* The site directories a Python at prefix (a venv: venv_prefix too) reads, and numpy there:
 * 1 found, else 0 with the reason in why. */
static int find_numpy(const char *prefix, const char *venv_prefix, int system_site, int minor,
                      char *why, size_t size) {
    char dirs[6][PATH_MAX];
    int n = 0;
    if (venv_prefix != NULL)
        pathf(dirs[n++], "%s/lib/python3.%d/site-packages", venv_prefix, minor);
    if (venv_prefix == NULL || system_site) {
        pathf(dirs[n++], "%s/lib/python3.%d/site-packages", prefix, minor);
        pathf(dirs[n++], "%s/lib64/python3.%d/site-packages", prefix, minor);
        pathf(dirs[n++], "%s/lib/python3/dist-packages", prefix); /* Debian */
        pathf(dirs[n++], "%s/local/lib/python3.%d/dist-packages", prefix, minor);
    }
    for (int i = 0; i < n; i++) {
        int found = numpy_in(dirs[i], minor);
        if (found == 1) return 1;
        if (found < 0) {
            snprintf(why, size, "numpy in %.2000s is built for another Python (no extension for "
                     "CPython 3.%d)", dirs[i], minor);
            return 0;
        }
    }
    snprintf(why, size, "no numpy in %.2000s%s", dirs[0], n > 1 ? " or the system site directories"
                                                           : "");
    return 0;
}

/* The installation a libpython belongs to: the nearest folder above it holding the standard
 * library of its version (up to three levels: prefix/lib/x86_64-linux-gnu/libpython...). */
static int prefix_of_libpython(const char *library, int minor, char *prefix) {
    if (realpath(library, prefix) == NULL) return 0;
    for (int up = 0; up < 3 && strcmp(prefix, "/") != 0; up++) {
        parent(prefix);
        if (has_stdlib(prefix, minor)) return 1;
    }
    return 0;
}

/* A Python executable's version and base prefix, and its venv if it is one. */
static int describe_python(const char *python, int *minor, char *prefix, char *venv, int *system) {
    char dir[PATH_MAX], cfg[PATH_MAX], line[PATH_MAX + 64];
    *minor = -1;
    venv[0] = '\0';
    *system = 0;
    pathf(dir, "%s", python);
    parent(dir); /* bin; pyvenv.cfg is in the venv's root (or, rarely, beside the executable) */
    for (int up = 0; up < 2 && !venv[0]; up++) {
        join(cfg, dir, "pyvenv.cfg");
        FILE *file = fopen(cfg, "r");
        if (file != NULL) {
            pathf(venv, "%s", dir);
            while (fgets(line, sizeof line, file) != NULL) {
                line[strcspn(line, "\r\n")] = '\0';
                char *value = strchr(line, '=');
                if (value == NULL) continue;
                *value++ = '\0';
                while (*value == ' ') value++;
                char *key = line + strspn(line, " ");
                key[strcspn(key, " ")] = '\0';
                if (strcmp(key, "home") == 0) {
                    pathf(prefix, "%s", value);
                    parent(prefix); /* home is the base installation's bin folder */
                } else if (strcmp(key, "version") == 0 || strcmp(key, "version_info") == 0) {
                    if (strncmp(value, "3.", 2) == 0) *minor = atoi(value + 2);
                } else if (strcmp(key, "include-system-site-packages") == 0) {
                    *system = strcmp(value, "true") == 0;
                }
            }
            fclose(file);
        }
        parent(dir);
    }
    if (!venv[0]) {
        char real[PATH_MAX];
        if (realpath(python, real) == NULL) return 0;
        *minor = minor_in_name(real, "python");
        pathf(prefix, "%s", real);
        parent(prefix);
        parent(prefix);
    }
    return *minor >= 0;
}

/* A script is not a Python executable (a pyenv shim on PATH, say): 1 if it starts with #!. */
static int is_script(const char *path) {
    char magic[2] = "";
    FILE *file = fopen(path, "rb");
    if (file == NULL) return 0;
    size_t n = fread(magic, 1, 2, file);
    fclose(file);
    return n == 2 && magic[0] == '#' && magic[1] == '!';
}

/* Judge one candidate (python or libpython may be NULL); on success fill the choice. Returns
 * 1 chosen, 0 rejected (with a note), -1 skipped (an environment already judged). */
static int judge(Search *s, const char *origin, const char *python, const char *library,
                 PythonChoice *choice) {
    char prefix[PATH_MAX] = "", venv[PATH_MAX] = "", lib[PATH_MAX] = "", why[PATH_MAX + 256];
    int minor = -1, system = 0;
    const char *shown = python ? python : library;
    if (python != NULL) {
        if (!exists(python)) { note(s, "%s %s: does not exist", origin, python); return 0; }
        if (access(python, X_OK) != 0) {
            note(s, "%s %s: not executable", origin, python);
            return 0;
        }
        if (is_script(python)) {
            note(s, "%s %s: a script (a pyenv shim?), not a Python executable", origin, python);
            return 0;
        }
        if (!describe_python(python, &minor, prefix, venv, &system)) {
            note(s, "%s %s: cannot tell its version (not a CPython 3 installation?)", origin,
                 python);
            return 0;
        }
    }
    if (library != NULL) {
        if (!exists(library)) { note(s, "%s %s: does not exist", origin, library); return 0; }
        int lib_minor = minor_in_name(library, "libpython");
        char real[PATH_MAX];
        if (lib_minor < 0 && realpath(library, real) != NULL)
            lib_minor = minor_in_name(real, "libpython");
        if (lib_minor < 0) {
            note(s, "%s %s: not named libpython3.X.so...: cannot tell its version", origin,
                 library);
            return 0;
        }
        if (python != NULL && lib_minor != minor) {
            note(s, "%s: libpython %s is Python 3.%d but %s is Python 3.%d", origin, library,
                 lib_minor, python, minor);
            return 0;
        }
        minor = lib_minor;
        pathf(lib, "%s", library);
    } else if (minor >= 0) { /* derive libpython from the Python's installation */
        static const char *const dirs[] = {"lib", "lib64", "lib/x86_64-linux-gnu"};
        for (size_t i = 0; i < 3 && !lib[0]; i++) {
            pathf(lib, "%s/%s/libpython3.%d.so.1.0", prefix, dirs[i], minor);
            if (!exists(lib)) lib[0] = '\0';
        }
        if (!lib[0]) {
            note(s, "%s %s: no libpython3.%d.so.1.0 in %s/lib (a Python built without "
                 "--enable-shared, or Debian/Ubuntu without the libpython3.%d package; set "
                 "SONOTRACK_LIBPYTHON)", origin, python, minor, prefix, minor);
            return 0;
        }
    }
    /* one environment, one line: a venv by its folder, an installation by its libpython */
    char key[PATH_MAX];
    if (venv[0]) pathf(key, "%s", venv);
    else if (realpath(lib, key) == NULL) pathf(key, "%s", lib);
    for (int i = 0; i < s->nseen; i++)
        if (strcmp(s->seen[i], key) == 0) return -1;
    if (s->nseen < 16) pathf(s->seen[s->nseen++], "%s", key);
    if (minor < s->build_minor) {
        note(s, "%s %s: Python 3.%d; the FMU needs 3.%d or newer", origin, shown, minor,
             s->build_minor);
        return 0;
    }
    char lib_prefix[PATH_MAX];
    if (!prefix_of_libpython(lib, minor, lib_prefix)) {
        note(s, "%s %s: no standard library of Python 3.%d (lib/python3.%d with os.py, "
             "encodings, lib-dynload) in the folders above %s", origin, shown, minor, minor, lib);
        return 0;
    }
    if (python == NULL) {
        pathf(prefix, "%s", lib_prefix);
    } else {
        char real_prefix[PATH_MAX];
        if (realpath(prefix, real_prefix) == NULL || strcmp(real_prefix, lib_prefix) != 0) {
            note(s, "%s: libpython %s belongs to the Python in %s, but %s is the one in %s",
                 origin, lib, lib_prefix, python, prefix);
            return 0;
        }
        if (!has_stdlib(prefix, minor)) {
            note(s, "%s %s: no standard library in %s/lib/python3.%d", origin, python, prefix,
                 minor);
            return 0;
        }
    }
    if (!s->without_numpy &&
        !find_numpy(prefix, venv[0] ? venv : NULL, system, minor, why, sizeof why)) {
        note(s, "%s %s (Python 3.%d): %s", origin, shown, minor, why);
        return 0;
    }
    pathf(choice->libpython, "%s", lib);
    if (python != NULL) pathf(choice->program, "%s", python);
    else pathf(choice->program, "%s/bin/python3.%d", prefix, minor);
    snprintf(choice->origin, sizeof choice->origin, "%s", origin);
    choice->minor = minor;
    return 1;
}

/* Every executable called name on PATH, in PATH order. */
static int from_path(Search *s, const char *name, PythonChoice *choice) {
    const char *path = getenv("PATH");
    char origin[64], file[PATH_MAX];
    snprintf(origin, sizeof origin, "%.40s on PATH", name);
    int found = 0;
    for (const char *dir = path; dir != NULL && *dir;) {
        const char *end = strchr(dir, ':');
        size_t n = end ? (size_t)(end - dir) : strlen(dir);
        if (n > 0 && n < PATH_MAX - 64) {
            pathf(file, "%.*s/%s", (int)n, dir, name);
            if (access(file, X_OK) == 0) {
                found = 1;
                if (judge(s, origin, file, NULL, choice) == 1) return 1;
            }
        }
        dir = end ? end + 1 : NULL;
    }
    if (!found) note(s, "%s: not found", origin);
    return 0;
}

int find_python(const Binding *b, const char *loaded, PythonChoice *choice, char *error,
                size_t size) {
    Search *s = calloc(1, sizeof *s);
    char *places = calloc(1, 8192);
    if (s == NULL || places == NULL) {
        free(s);
        free(places);
        snprintf(error, size, "out of memory");
        return -1;
    }
    s->text = places;
    s->size = 8192;
    s->build_minor = strncmp(b->python_version, "3.", 2) == 0 ? atoi(b->python_version + 2) : 0;
    int chosen = 0;
    const char *python = getenv("SONOTRACK_PYTHON"), *library = getenv("SONOTRACK_LIBPYTHON");
    if (python && !python[0]) python = NULL;
    if (library && !library[0]) library = NULL;
    if (loaded != NULL) { /* a libpython the host process has already loaded: that one or none */
        chosen = judge(s, "libpython already loaded in the host process", NULL, loaded,
                       choice) == 1;
    } else if (python || library) {
        const char *origin = python && library ? "SONOTRACK_PYTHON and SONOTRACK_LIBPYTHON"
                             : python ? "SONOTRACK_PYTHON" : "SONOTRACK_LIBPYTHON";
        chosen = judge(s, origin, python, library, choice) == 1;
    } else {
        note(s, "SONOTRACK_PYTHON, SONOTRACK_LIBPYTHON: not set");
        if (b->runtime != NULL) {
            char file[PATH_MAX];
            pathf(file, "%s/lib/libpython3.%d.so.1.0", b->runtime, s->build_minor);
            s->without_numpy = b->runtime_without_numpy;
            chosen = judge(s, "carried in the FMU", NULL, file, choice) == 1;
            s->without_numpy = 0;
        } else {
            note(s, "carried in the FMU: none (not a portable build)");
        }
        chosen = chosen || judge(s, "recorded at build", b->python[0] ? b->python : NULL,
                                 b->libpython[0] ? b->libpython : NULL, choice) == 1;
        char name[32];
        snprintf(name, sizeof name, "python3.%d", s->build_minor);
        chosen = chosen || from_path(s, name, choice) || from_path(s, "python3", choice);
        int standard = 0;
        for (int minor = s->build_minor; !chosen && minor <= s->build_minor + LATER_MINORS;
             minor++) {
            for (size_t i = 0; !chosen && i < sizeof STANDARD_DIRS / sizeof *STANDARD_DIRS; i++) {
                char file[PATH_MAX];
                pathf(file, "%s/libpython3.%d.so.1.0", STANDARD_DIRS[i], minor);
                if (!exists(file)) continue;
                standard = 1;
                chosen = judge(s, "standard location", NULL, file, choice) == 1;
            }
        }
        if (!chosen && !standard)
            note(s, "standard locations (/usr/lib/x86_64-linux-gnu, /usr/lib64, /usr/local/lib, "
                 "/usr/lib): no libpython3.%d to 3.%d", s->build_minor,
                 s->build_minor + LATER_MINORS);
    }
    if (!chosen && b->runtime != NULL && loaded == NULL && !python && !library)
        snprintf(error, size, "no Python 3.%d or newer with numpy to run this FMU in a host that "
                 "runs no Python; tried: %s. Fix: this FMU carries its own Python in %.1000s: "
                 "unzip the whole FMU again (a file of it is missing or changed), or build it "
                 "again with `sonotrack build --portable`", s->build_minor, places, b->runtime);
    else if (!chosen)
        snprintf(error, size, "no Python 3.%d or newer with numpy to run this FMU in a host that "
                 "runs no Python; tried: %s. Fix: install Python 3.%d with numpy (Debian/Ubuntu: "
                 "apt-get install libpython3.%d python3-numpy), or set SONOTRACK_PYTHON to a "
                 "python3 executable whose environment has numpy (a venv's bin/python works; "
                 "add SONOTRACK_LIBPYTHON=/path/to/libpython3.X.so.1.0 if its libpython is not "
                 "in its prefix's lib folder)", s->build_minor, places, s->build_minor,
                 s->build_minor);
    free(places);
    free(s);
    return chosen ? 0 : -1;
}
