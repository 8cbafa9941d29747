/* The binding table resources/sonotrack_binding.txt (written by `sonotrack build`) and where the
 * FMU's resources are. Pure C: nothing here touches Python except dropping interned names.
 */
#define _GNU_SOURCE
#include <ctype.h>
#include <dlfcn.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sonotrack_fmi2.h"

const char *const TYPE_NAMES[5] = {"(none)", "Real", "Integer", "Boolean", "String"};
static const char *const CAUSALITY_NAMES[] = {"parameter", "calculatedParameter", "input",
                                              "output", "local", "independent"};

int lookup(const char *word, const char *const *names, int n) {
    for (int i = 0; i < n; i++)
        if (strcmp(word, names[i]) == 0) return i;
    return -1;
}

void free_binding(Binding *b, int python_alive) {
    for (size_t i = 0; i < b->nvars; i++) {
        free(b->vars[i].name);
        if (b->vars[i].attribute && python_alive) py.DecRef(b->vars[i].attribute);
    }
    free(b->vars);
    free(b->guid); free(b->libpython); free(b->python); free(b->python_version);
    free(b->package); free(b->entry); free(b->class_name); free(b->runtime);
    memset(b, 0, sizeof *b);
}

/* The optional runtime line names a folder relative to the FMU's root (the folder above the
 * table's resources/): made absolute here; a name that climbs out of the FMU is refused. */
static int runtime_folder(const char *table, Binding *b, char *error, size_t size) {
    if (b->runtime[0] == '/' || strstr(b->runtime, "..") != NULL) {
        snprintf(error, size, "%.900s: runtime %.200s is not a folder inside the FMU", table,
                 b->runtime);
        return -1;
    }
    char *root = strdup(table);
    if (root == NULL) return -1;
    for (int up = 0; up < 2; up++) { /* <root>/resources/sonotrack_binding.txt -> <root> */
        char *slash = strrchr(root, '/');
        if (slash != NULL) *slash = '\0';
        else root[0] = '\0';
    }
    char *folder = malloc(strlen(root) + strlen(b->runtime) + 2);
    if (folder != NULL) sprintf(folder, "%s/%s", root[0] ? root : ".", b->runtime);
    free(root);
    free(b->runtime);
    b->runtime = folder;
    return folder != NULL ? 0 : -1;
}

int read_binding(const char *path, Binding *b, char *error, size_t size) {
    static const char *const variabilities[] = {"constant", "fixed", "tunable", "discrete",
                                                "continuous"};
    static const char *const initials[] = {"-", "exact", "approx", "calculated"};
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
        else if (n == 2 && strcmp(fields[0], "runtime") == 0) slot = &b->runtime;
        if (n == 2 && strcmp(fields[0], "runtime_numpy") == 0) { /* a portable FMU's */
            b->runtime_without_numpy = strcmp(fields[1], "no") == 0;
            if (!b->runtime_without_numpy && strcmp(fields[1], "yes") != 0) { failed = 1; break; }
            continue;
        }
        if (slot != NULL) {
            free(*slot);
            if ((*slot = strdup(fields[1])) == NULL) { failed = 1; break; }
            continue;
        }
        if (n == 7 && strcmp(fields[0], "var") == 0) {
            char *end;
            unsigned long vr = strtoul(fields[1], &end, 10);
            int type = lookup(fields[2], TYPE_NAMES, 5);
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
            v->initial = initial;
            if ((v->name = strdup(fields[6])) == NULL) { failed = 1; break; }
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
    return b->runtime != NULL ? runtime_folder(path, b, error, size) : 0;
}

/* file:///a%20b/resources -> /a b/resources (no trailing slash). */
char *path_from_uri(const char *uri) {
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
        unsigned int code; /* a '%' not followed by two hex digits stays as it is */
        if (p[0] == '%' && isxdigit((unsigned char)p[1]) && isxdigit((unsigned char)p[2]) &&
            sscanf(p + 1, "%2x", &code) == 1) {
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
char *resources_beside_binary(void) {
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
