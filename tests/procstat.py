"""What Linux's /proc says of a process: its parent and the CPU it has used so far (tests that
measure a child's CPU rather than wall time, which other processes' load would change)."""

import os
import pathlib


def stat(pid):
    """The fields of /proc/<pid>/stat after the command's name (which may hold spaces and
    parentheses): ``[0]`` the state, ``[1]`` the parent's pid, ``[11]``/``[12]`` user and
    system time in clock ticks. Raises OSError once the process is gone."""
    return pathlib.Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()


def cpu_seconds(pid=None, fields=None):
    """The CPU seconds (user + system) process ``pid`` has used so far (or those ``fields``
    of its stat say)."""
    fields = stat(pid) if fields is None else fields
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
