#!/usr/bin/env python3
"""Check that libevemu (the library behind evemu-play) reads the evemu files
marionette writes: its reader must accept the description and return every
event, with the same count of events and SYN_REPORT frames as marionette.

usage: libevemu_reads.py MARIONETTE_BINARY FILE.evemu...   (needs libevemu3)
"""
import ctypes
import json
import subprocess
import sys

lib = ctypes.CDLL("libevemu.so.3")
libc = ctypes.CDLL("libc.so.6")
libc.fopen.restype = ctypes.c_void_p
libc.fopen.argtypes = [ctypes.c_char_p, ctypes.c_char_p]
libc.fclose.argtypes = [ctypes.c_void_p]
lib.evemu_new.restype = ctypes.c_void_p
lib.evemu_new.argtypes = [ctypes.c_char_p]
lib.evemu_delete.argtypes = [ctypes.c_void_p]
lib.evemu_get_name.restype = ctypes.c_char_p
lib.evemu_get_name.argtypes = [ctypes.c_void_p]
lib.evemu_read.argtypes = [ctypes.c_void_p, ctypes.c_void_p]


class TimeVal(ctypes.Structure):
    _fields_ = [("sec", ctypes.c_long), ("usec", ctypes.c_long)]


class InputEvent(ctypes.Structure):
    _fields_ = [("time", TimeVal), ("type", ctypes.c_uint16), ("code", ctypes.c_uint16), ("value", ctypes.c_int32)]


lib.evemu_read_event.argtypes = [ctypes.c_void_p, ctypes.POINTER(InputEvent)]

failed = 0
binary, files = sys.argv[1], sys.argv[2:]
for path in files:
    fp = libc.fopen(path.encode(), b"r")
    dev = lib.evemu_new(None)
    if lib.evemu_read(dev, fp) <= 0:
        print(f"FAIL {path}: libevemu refuses the description")
        failed += 1
        continue
    ev, events, frames = InputEvent(), 0, 0
    while lib.evemu_read_event(fp, ctypes.byref(ev)) > 0:
        events += 1
        frames += ev.type == 0 and ev.code == 0
    name = lib.evemu_get_name(dev).decode()
    libc.fclose(fp)
    lib.evemu_delete(dev)
    ours = json.loads(subprocess.run([binary, "inspect", path], capture_output=True, check=True).stdout)
    e_lines = sum(1 for line in open(path) if line.startswith("E:"))
    ok = events == e_lines and frames == ours["frames"] and name == ours["device"]
    print(f"{'ok  ' if ok else 'FAIL'} {path}: libevemu read {events} events, {frames} frames, name {name!r}; "
          f"file has {e_lines} events, marionette {ours['frames']} frames")
    failed += not ok
print(f"{len(files) - failed} passed, {failed} failed")
sys.exit(1 if failed else 0)
