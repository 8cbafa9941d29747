"""Which process wrote a record, and whether that process still runs.

A run's ``summary.json`` names the process that writes it with :func:`process_record`:

    {"pid": 4242, "host": "lab-3", "started": 1764788461.37,
     "boot_id": "6c1f0e2a-...", "start_ticks": 1234567}

``started`` is when the process started, in seconds since the epoch (for people to read).
Whether the process still runs is judged by :func:`process_state` from the exact fields: on
the same host and since the same boot (``boot_id``, Linux's
``/proc/sys/kernel/random/boot_id``), a process with that id must exist, not be a zombie, and
have started at the same kernel clock tick (``start_ticks``, field 22 of ``/proc/PID/stat``).
An id the kernel handed to a newer process after the recorded one ended (pid reuse) has
another start tick; after a reboot every id names another process. ``started`` itself is not
compared: Linux derives it from a boot time that can drift by a second between reads.

The answer is :data:`ALIVE`, :data:`GONE` or :data:`UNKNOWN`. Unknown means this process cannot
tell: the record names another host (its processes are not visible here), or it lacks the
fields to judge. Where ``/proc`` is missing (not Linux) a record holds only ``pid``, ``host``
and ``started: null``, and a process with that id counts as the recorded one.

Examples
--------
>>> process_state(process_record())
'alive'
"""

import os
import socket

__all__ = ["ALIVE", "GONE", "UNKNOWN", "describe", "process_record", "process_state"]

ALIVE = "alive"
GONE = "gone"
UNKNOWN = "unknown"

_PROC = "/proc"


def _stat_fields(pid):
    """The fields of ``/proc/PID/stat`` after the command name (field 3 on), or None.

    The command name (field 2) is in parentheses and may itself hold spaces and parentheses,
    so the fields start after the last ``)``.
    """
    try:
        with open(f"{_PROC}/{pid}/stat", encoding="ascii", errors="replace") as stream:
            text = stream.read()
    except OSError:
        return None
    return text[text.rfind(")") + 2:].split()


def _start_ticks(pid):
    """(state letter, start time in clock ticks since boot) of ``pid``, or None."""
    fields = _stat_fields(pid)
    if fields is None or len(fields) < 20:
        return None
    return fields[0], int(fields[19])


def _boot_id():
    try:
        with open(f"{_PROC}/sys/kernel/random/boot_id", encoding="ascii") as stream:
            return stream.read().strip() or None
    except OSError:
        return None


def _boot_time():
    """Seconds since the epoch at boot (``btime`` of ``/proc/stat``), or None."""
    try:
        with open(f"{_PROC}/stat", encoding="ascii") as stream:
            for line in stream:
                if line.startswith("btime "):
                    return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return None


def process_record(pid=None):
    """A record naming a process: its id, host and start time (see the module docstring).

    Parameters
    ----------
    pid : int, optional
        The process (default: this one).

    Returns
    -------
    dict
        ``pid``, ``host``, ``started`` and, on Linux, ``boot_id`` and ``start_ticks``.
    """
    pid = os.getpid() if pid is None else int(pid)
    record = {"pid": pid, "host": socket.gethostname(), "started": None}
    stat = _start_ticks(pid)
    boot_id, boot_time = _boot_id(), _boot_time()
    if stat is not None and boot_id is not None and boot_time is not None:
        ticks = stat[1]
        record["started"] = round(boot_time + ticks / os.sysconf("SC_CLK_TCK"), 2)
        record["boot_id"] = boot_id
        record["start_ticks"] = ticks
    return record


def _exists(pid):
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:   # another user's process: it exists
        return True
    return True


def process_state(record):
    """Whether the process a record names still runs here: ``"alive"``, ``"gone"`` or
    ``"unknown"``.

    Parameters
    ----------
    record : dict
        As :func:`process_record` made it (anything else is ``"unknown"``).

    Returns
    -------
    str
        :data:`ALIVE`, :data:`GONE` (no such process, a zombie, another process under the same
        id, or a reboot since) or :data:`UNKNOWN` (another host, or a record without the
        fields to judge).
    """
    if not isinstance(record, dict):
        return UNKNOWN
    pid, host = record.get("pid"), record.get("host")
    if (not isinstance(pid, int) or isinstance(pid, bool) or pid <= 0
            or not isinstance(host, str) or host != socket.gethostname()):
        return UNKNOWN
    boot_id, ticks = record.get("boot_id"), record.get("start_ticks")
    here = _boot_id()
    if isinstance(boot_id, str) and isinstance(ticks, int) and here is not None:
        if boot_id != here:
            return GONE
        stat = _start_ticks(pid)
        # Z: ended, not yet reaped by its parent; X: being removed
        if stat is None or stat[0] in ("Z", "X") or stat[1] != ticks:
            return GONE
        return ALIVE
    if "boot_id" in record or "start_ticks" in record:
        return UNKNOWN   # recorded on Linux, read where /proc is missing: cannot compare
    return ALIVE if _exists(pid) else GONE


def describe(record):
    """``pid 4242 on lab-3`` (the words a message uses for a recorded process)."""
    if not isinstance(record, dict):
        return "an unrecorded process"
    return f"pid {record.get('pid')} on {record.get('host')}"

