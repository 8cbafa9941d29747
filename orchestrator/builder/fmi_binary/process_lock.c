/* The process-wide lock of sonotrack's FMI binary, built as its own small library,
 * libsonotrack_fmi2_lock.so.1, that every FMU carries beside its binary.
 *
 * Each unzipped FMU is another copy of the main library, with its own statics, so a mutex there
 * guards one copy only; two copies starting Python from two threads at once crash the host. This
 * library holds the one mutex of the process (and the reason a start of Python failed, which every
 * copy must give from then on): the main library needs it by name (DT_NEEDED,
 * found through RUNPATH $ORIGIN), and the dynamic loader maps a needed library of a given name
 * once per process, handing every later copy the one already loaded. Its interface is frozen:
 * another one gets another soname, never a change under this one.
 */
#include "sonotrack_fmi2.h"

#ifndef SONOTRACK_SOURCE_SHA256
#error "define SONOTRACK_SOURCE_SHA256 as the quoted orchestrator.builder.fmi_binary.source_hash() (make does)"
#endif

/* The sources it was compiled from, checked by `sonotrack build` as for the main library
 * (retain: nothing refers to it, and the linker would drop it). */
__attribute__((used, retain)) static const char SOURCE_ID[] =
    "sonotrack-fmi2-sources sha256 " SONOTRACK_SOURCE_SHA256;

static pthread_mutex_t process_lock = PTHREAD_MUTEX_INITIALIZER;
static char start_failure[START_FAILURE_SIZE];

pthread_mutex_t *sonotrack_fmi2_process_lock_v1(void) { return &process_lock; }

char *sonotrack_fmi2_start_failure_v1(void) { return start_failure; }
