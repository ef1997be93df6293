#!/usr/bin/env python3
"""Independent reader for cupid's .vtu files (VTK XML UnstructuredGrid, appended base64 data).

Standard library only (xml.etree + base64 + struct). Checks the structure against the VTK file
format (header_type UInt64, <AppendedData encoding="base64"> whose text is '_' then one base64
run per DataArray, at the DataArray's offset in characters after the '_': each run padded to a
multiple of 4 characters, '=' only at its end, decoding to a UInt64 byte count and exactly that
many bytes; runs contiguous and covering the appended data; block sizes matching
NumberOfPoints/NumberOfCells x NumberOfComponents, cell offsets increasing and ending at the
connectivity length, connectivity inside the points) and dumps every array as text, one value
per line, floats with repr() (exact round trip):

    points N
    cells M
    array SECTION NAME TYPE COMPONENTS COUNT
    value
    ...

Usage: read_vtu.py FILE.vtu [OUT.txt]   (exit status 1 with a message if the file is wrong)
"""
import base64
import binascii
import re
import struct
import sys
import xml.etree.ElementTree as ET

TYPES = {"Float64": ("d", 8), "Float32": ("f", 4), "Int64": ("q", 8), "Int32": ("i", 4),
         "UInt64": ("Q", 8), "UInt8": ("B", 1)}
RUN = re.compile(rb"[A-Za-z0-9+/]*(?:[A-Za-z0-9+/]{2}==|[A-Za-z0-9+/]{3}=)?")


def fail(msg):
    sys.exit("read_vtu.py: " + msg)


def decode(text, what):
    """Bytes of one padded base64 run (validated: alphabet, length, '=' only at its end)."""
    if len(text) % 4 or RUN.fullmatch(text) is None:
        fail("%s: not one padded base64 run" % what)
    try:
        return base64.b64decode(text, validate=True)
    except binascii.Error as e:
        fail("%s: %s" % (what, e))


def read(path):
    data = open(path, "rb").read()
    tag = b'<AppendedData encoding="base64">'
    start = data.find(tag)
    if start < 0:
        fail("no base64 AppendedData")
    marker = data.find(b"_", start + len(tag))
    if marker < 0 or data[start + len(tag):marker].strip():
        fail("no '_' marker")
    base = marker + 1
    tail = data.rfind(b"</AppendedData>")
    if tail < 0 or data[tail:].split() != [b"</AppendedData>", b"</VTKFile>"]:
        fail("file does not end with </AppendedData></VTKFile>")
    text = data[base:tail].rstrip()  # the runs, back to back
    root = ET.fromstring(data[:start] + b"</VTKFile>")
    if root.tag != "VTKFile" or root.get("type") != "UnstructuredGrid":
        fail("not an UnstructuredGrid")
    if root.get("header_type") != "UInt64":
        fail("header_type is not UInt64")
    if root.get("compressor") is not None:
        fail("compressed data")
    order = {"LittleEndian": "<", "BigEndian": ">"}.get(root.get("byte_order"))
    if order is None:
        fail("bad byte_order")
    pieces = root.findall("UnstructuredGrid/Piece")
    if len(pieces) != 1:
        fail("expected one Piece")
    piece = pieces[0]
    npts, ncells = int(piece.get("NumberOfPoints")), int(piece.get("NumberOfCells"))
    arrays, blocks = [], []
    for section in ("PointData", "CellData", "Points", "Cells"):
        for el in piece.findall(section + "/DataArray"):
            name = el.get("Name")
            if el.get("format") != "appended":
                fail("array %s is not appended" % name)
            code, size = TYPES[el.get("type")]
            ncomp = int(el.get("NumberOfComponents", "1"))
            off = int(el.get("offset"))
            head = decode(text[off:off + 12], "array %s" % name)
            if len(head) < 8:
                fail("array %s: no byte count" % name)
            (nbytes,) = struct.unpack(order + "Q", head[:8])
            end = off + (8 + nbytes + 2) // 3 * 4
            if end > len(text) or nbytes % size:
                fail("array %s: bad size %d" % (name, nbytes))
            raw = decode(text[off:end], "array %s" % name)
            if len(raw) != 8 + nbytes:
                fail("array %s: %d bytes after the count, expected %d" % (name, len(raw) - 8,
                                                                          nbytes))
            count = nbytes // size
            values = struct.unpack(order + code * count, raw[8:])
            blocks.append((off, end))
            arrays.append((section, name, el.get("type"), ncomp, values))
    blocks.sort()
    for (a0, a1), (b0, b1) in zip(blocks, blocks[1:]):
        if a1 != b0:
            fail("appended runs overlap or leave a gap")
    if blocks and (blocks[0][0] != 0 or blocks[-1][1] != len(text)):
        fail("appended data has gaps at its ends")
    named = {(s, n): v for s, n, _, _, v in arrays}
    for s, n, _, ncomp, v in arrays:
        expected = {"PointData": npts, "CellData": ncells, "Points": npts}.get(s)
        if expected is not None and len(v) != expected * ncomp:
            fail("%s/%s has %d values, expected %d" % (s, n, len(v), expected * ncomp))
    conn, offs = named[("Cells", "connectivity")], named[("Cells", "offsets")]
    if len(offs) != ncells or len(named[("Cells", "types")]) != ncells:
        fail("offsets/types do not match NumberOfCells")
    prev = 0
    for o in offs:
        if o <= prev:
            fail("cell offsets do not increase")
        prev = o
    if prev != len(conn) or any(c < 0 or c >= npts for c in conn):
        fail("connectivity does not match offsets or points")
    return npts, ncells, arrays


def main():
    if len(sys.argv) not in (2, 3):
        fail("usage: read_vtu.py FILE.vtu [OUT.txt]")
    npts, ncells, arrays = read(sys.argv[1])
    out = open(sys.argv[2], "w") if len(sys.argv) == 3 else sys.stdout
    out.write("points %d\ncells %d\n" % (npts, ncells))
    for section, name, typ, ncomp, values in arrays:
        out.write("array %s %s %s %d %d\n" % (section, name, typ, ncomp, len(values)))
        out.write("".join(repr(v) + "\n" for v in values))
    out.close()


if __name__ == "__main__":
    main()
