"""LCM event logs read the way kincal's C++ reader reads them (kincal/io/lcm_log_reader.h):
every header checked against the bytes left, and a file that is not a log, or a damaged or
cut-short one, named with the byte where it goes wrong. Shared by the scripts beside this
file (kincal export --format mcap, kincal view).

The format is LCM's logger's: per event a big-endian header (sync word 0xEDA1DA01, event
number, timestamp in microseconds, channel length, data length), the channel, the data.
"""

import os
import struct

LCM_SYNC = 0xEDA1DA01
LCM_HEADER = struct.Struct(">IqqII")
MAX_CHANNEL = 256


class LogError(Exception):
    pass


def read_events_at(path):
    """(channel, data, timestamp in us, byte offset) of every event, in file order."""
    try:
        size = os.path.getsize(path)
        f = open(path, "rb")
    except OSError as e:
        raise LogError(f"{path}: {e.strerror}") from e
    if size == 0:
        f.close()
        raise LogError(f"{path}: the log is empty (0 bytes)")
    n = 0
    with f:
        while True:
            at = f.tell()
            head = f.read(LCM_HEADER.size)
            if not head:
                return
            if len(head) < LCM_HEADER.size:
                raise LogError(f"{path}: cut short at byte {at}: a header of {len(head)} bytes")
            sync, _, utime, clen, dlen = LCM_HEADER.unpack(head)
            if sync != LCM_SYNC:
                what = "not an LCM log" if n == 0 else f"damaged after event {n}"
                raise LogError(f"{path}: {what}: no LCM sync word at byte {at}")
            if clen == 0 or clen > MAX_CHANNEL or at + LCM_HEADER.size + clen + dlen > size:
                raise LogError(f"{path}: damaged or cut short at byte {at}: event {n + 1} claims "
                               f"{clen} + {dlen} bytes, {size - at - LCM_HEADER.size} are left")
            channel = f.read(clen).decode("utf-8", errors="replace")
            data = f.read(dlen)
            n += 1
            yield channel, data, utime, at


def read_event_at(path, offset):
    """The data of the event at `offset` (from read_events_at)."""
    with open(path, "rb") as f:
        f.seek(offset)
        sync, _, _, clen, dlen = LCM_HEADER.unpack(f.read(LCM_HEADER.size))
        if sync != LCM_SYNC:
            raise LogError(f"{path}: no LCM event at byte {offset}")
        f.seek(clen, os.SEEK_CUR)
        return f.read(dlen)
