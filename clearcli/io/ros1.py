"""ROS 1 bags (format 2.0) read record by record in file order: the reader for bags whose
index is missing or unreadable (a recording cut short, a truncated copy, an unindexed
bag). It parses the record headers and chunks itself (rosbags' reader needs the index);
`Damage` marks where the records stop making sense, so that `clearcli.io.rosbag` can
report every complete frame before it."""

from __future__ import annotations

import bz2
import io
import os
import struct
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import BinaryIO

from lz4.frame import decompress as lz4_decompress  # type: ignore[import-untyped]  # lz4 ships no type information

from clearcli.io.mcap import error_reason

# --- ROS 1: records in file order (bags without a usable index) ------------------------

_OP_MSGDATA, _OP_BAGHEADER, _OP_IDXDATA, _OP_CHUNK, _OP_CHUNK_INFO, _OP_CONNECTION = 2, 3, 4, 5, 6, 7
_MAX_HEADER = 1 << 24  # 16 MiB: far beyond any real record header; larger means garbage


class Damage(Exception):
    """The record stream stops making sense here."""


@dataclass(frozen=True)
class _Ros1Conn:
    id: int
    topic: str
    msgtype: str  # as written (ROS 1 spelling)
    msgdef: str
    md5sum: str


@dataclass(frozen=True)
class Ros1Msg:
    conn: int
    time_ns: int
    data: bytes | None  # None when not asked for


def _fields(blob: bytes) -> dict[str, bytes]:
    out: dict[str, bytes] = {}
    pos = 0
    while pos < len(blob):
        if pos + 4 > len(blob):
            raise Damage("record header field cut short")
        (size,) = struct.unpack_from("<I", blob, pos)
        pos += 4
        if pos + size > len(blob):
            raise Damage("record header field longer than its header")
        name, sep, value = blob[pos : pos + size].partition(b"=")
        if not sep:
            raise Damage("record header field without '='")
        out[name.decode("latin-1")] = value
        pos += size
    return out


def _u32(fields: dict[str, bytes], name: str) -> int:
    try:
        return struct.unpack("<I", fields[name])[0]
    except (KeyError, struct.error):
        raise Damage(f"record lacks a valid {name!r} field") from None


def _text(fields: dict[str, bytes], name: str) -> str:
    if name not in fields:
        raise Damage(f"record lacks a {name!r} field")
    return fields[name].decode("utf-8", errors="replace")


class Ros1Stream:
    """Records of a ROS 1 bag in file order: connections and messages.

    Message data is read only for connections `want(conn)` accepts; the others are skipped
    (seeked over in uncompressed chunks). Raises Damage where the file stops making sense,
    including when it ends before the index its header announces.
    """

    def __init__(self, fp: BinaryIO, size: int, want: Callable[[_Ros1Conn], bool]) -> None:
        self.fp = fp
        self.size = size
        self.want = want
        self.conns: dict[int, _Ros1Conn] = {}
        self.index_pos = 0
        self.chunks = 0

    def _read(self, src: BinaryIO, n: int, what: str) -> bytes:
        data = src.read(n)
        if len(data) != n:
            raise Damage(f"the file ends inside {what}")
        return data

    def _record(self, src: BinaryIO, end: int, cut_ok: bool = False) -> tuple[dict[str, bytes], int] | None:
        """(header fields, data length) with `src` at the data; None at a clean end.

        `cut_ok`: the data may run past `end` (an uncompressed chunk whose records are
        read one by one, so that a cut chunk still gives its complete messages).
        """
        start = src.tell()
        if start >= end:
            return None
        raw = src.read(4)
        if not raw:
            return None
        if len(raw) < 4:
            raise Damage("the file ends inside a record")
        (hlen,) = struct.unpack("<I", raw)
        if hlen > _MAX_HEADER or start + 4 + hlen > end:
            raise Damage(f"record header at byte {start} is {hlen} bytes: garbage or cut")
        fields = _fields(self._read(src, hlen, "a record header"))
        raw = self._read(src, 4, "a record")
        (dlen,) = struct.unpack("<I", raw)
        if src.tell() + dlen > end and not cut_ok:
            raise Damage(f"the {'file' if end >= self.size else 'chunk'} ends inside a record's data")
        if "op" not in fields or len(fields["op"]) != 1:
            raise Damage(f"record at byte {start} has no op code")
        return fields, dlen

    def _connection(self, fields: dict[str, bytes], data: bytes) -> _Ros1Conn | None:
        cid = _u32(fields, "conn")
        inner = _fields(data)
        conn = _Ros1Conn(
            cid,
            _text(fields, "topic"),
            _text(inner, "type"),
            inner.get("message_definition", b"").decode("utf-8", errors="replace"),
            inner.get("md5sum", b"").decode("latin-1"),
        )
        if cid in self.conns:
            return None
        self.conns[cid] = conn
        return conn

    def _inner(self, src: BinaryIO, end: int) -> Iterator[_Ros1Conn | Ros1Msg]:
        """Connection and message records of one chunk's data, from `src` up to `end`."""
        while True:
            rec = self._record(src, end)
            if rec is None:
                return
            fields, dlen = rec
            op = fields["op"][0]
            if op == _OP_CONNECTION:
                conn = self._connection(fields, self._read(src, dlen, "a connection record"))
                if conn is not None:
                    yield conn
            elif op == _OP_MSGDATA:
                cid = _u32(fields, "conn")
                time = fields.get("time", b"")
                if len(time) != 8:
                    raise Damage("message record without a valid time")
                sec, nsec = struct.unpack("<II", time)
                conn = self.conns.get(cid)
                if conn is None:
                    raise Damage(f"message on unknown connection {cid}")
                if self.want(conn):
                    data: bytes | None = self._read(src, dlen, "a message")
                else:
                    src.seek(dlen, os.SEEK_CUR)
                    data = None
                yield Ros1Msg(cid, sec * 1_000_000_000 + nsec, data)
            else:
                raise Damage(f"record of type {op} inside a chunk")

    def records(self) -> Iterator[_Ros1Conn | Ros1Msg]:
        fp = self.fp
        fp.seek(0)
        magic = fp.readline(64)
        if not magic.startswith(b"#ROSBAG V2.0"):
            raise Damage(f"unsupported bag version {magic[:12].decode('latin-1', 'replace')!r} (only V2.0 is read)")
        rec = self._record(fp, self.size)
        if rec is None or rec[0]["op"][0] != _OP_BAGHEADER:
            raise Damage("the bag header record is missing")
        fields, dlen = rec
        try:
            self.index_pos = struct.unpack("<Q", fields.get("index_pos", b""))[0]
        except struct.error:
            raise Damage("the bag header has no valid index_pos") from None
        if fields.get("encryptor"):
            raise Damage(f"encrypted bag ({fields['encryptor'].decode('latin-1')}) cannot be read")
        fp.seek(dlen, os.SEEK_CUR)
        while True:
            rec = self._record(fp, self.size, cut_ok=True)
            if rec is None:
                break
            fields, dlen = rec
            op = fields["op"][0]
            if op != _OP_CHUNK and fp.tell() + dlen > self.size:
                raise Damage("the file ends inside a record's data")
            if op == _OP_CHUNK:
                self.chunks += 1
                compression = fields.get("compression", b"none").decode("latin-1")
                if compression == "none":  # its records one by one: a cut chunk keeps its whole ones
                    chunk_end = fp.tell() + dlen
                    yield from self._inner(fp, min(chunk_end, self.size))
                    if chunk_end > self.size:
                        raise Damage(f"the file ends inside chunk {self.chunks}")
                    continue
                blob = self._read(fp, dlen, "a chunk")
                try:
                    if compression == "bz2":
                        raw = bz2.decompress(blob)
                    elif compression == "lz4":
                        raw = lz4_decompress(blob)
                    else:
                        raise Damage(f"chunk compression {compression!r} is not supported")
                except Damage:
                    raise
                except Exception as exc:
                    raise Damage(f"chunk {self.chunks} cannot be decompressed ({error_reason(exc)})") from None
                yield from self._inner(io.BytesIO(raw), len(raw))
            elif op == _OP_CONNECTION:
                conn = self._connection(fields, self._read(fp, dlen, "a connection record"))
                if conn is not None:
                    yield conn
            elif op in (_OP_IDXDATA, _OP_CHUNK_INFO):
                fp.seek(dlen, os.SEEK_CUR)
            else:
                raise Damage(f"unexpected record of type {op} at byte {fp.tell()}")
        if self.index_pos and self.size <= self.index_pos:  # no index section at all
            raise Damage(f"the file ends at byte {self.size}, before its index at byte {self.index_pos}")
