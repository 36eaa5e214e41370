"""Reading and writing 16-bit grayscale PNGs (TUM depth frames) fast: ISA-L's deflate and numpy's row filters.

A TUM depth frame is a 640x480 16-bit PNG whose rows are all Sub-filtered. Most of PIL's time decoding one is
zlib's inflate; ISA-L (``isal``) inflates the same stream several times faster, and undoing the Sub filter is a
running sum of each row's bytes modulo 256, two bytes a pixel apart: a third of PIL's time in all (measured:
docs/studies/odometry_constants.md). :func:`decode_gray16`
takes the PNGs this covers, non-interlaced 16-bit grayscale with None- or Sub-filtered rows, and leaves every other
PNG (other bit depths or colour types, interlacing, Up, Average or Paeth rows, as PIL itself writes) to PIL.
:func:`encode_gray16` writes what it reads fast: every row Sub-filtered, deflated by ISA-L.
"""
from __future__ import annotations

import struct

import numpy as np

from dgmm.errors import DataError, needs

with needs("odometry"):
    from isal import isal_zlib

_SIGNATURE = b"\x89PNG\r\n\x1a\n"
_NONE, _SUB = 0, 1  # PNG row filter types


def decode_gray16(data, name="PNG"):
    """The pixels of a PNG's bytes if it is 16-bit grayscale, non-interlaced, with None- or Sub-filtered rows.

    Parameters
    ----------
    data : bytes
        The whole file.
    name : str
        Names the file in errors.

    Returns
    -------
    pixels : ndarray of big-endian uint16 (``">u2"``, as PNG stores them), shape (height, width), or None
        None when the PNG is another kind (PIL decodes those).

    Raises
    ------
    DataError
        A chunk's CRC does not match, the image data do not inflate, or they hold the wrong number of bytes.
    """
    if not data.startswith(_SIGNATURE):
        return None
    header, compressed, position = None, [], len(_SIGNATURE)
    while position + 12 <= len(data):
        (length,), kind = struct.unpack(">I", data[position:position + 4]), data[position + 4:position + 8]
        end = position + 8 + length
        if end + 4 > len(data):
            raise DataError(f"{name}: corrupt PNG (chunk {kind!r} truncated)")
        body, (crc,) = data[position + 8:end], struct.unpack(">I", data[end:end + 4])
        if _crc(kind, body) != crc:
            raise DataError(f"{name}: corrupt PNG (chunk {kind!r}: its CRC does not match)")
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            compressed.append(body)
        elif kind == b"IEND":
            break
        position += 12 + length
    if header is None or header[2:] != (16, 0, 0, 0, 0):  # bit depth 16, grayscale, deflate, filters 0, no interlace
        return None
    width, height = header[:2]
    try:
        raw = isal_zlib.decompress(b"".join(compressed))
    except isal_zlib.error as exc:
        raise DataError(f"{name}: corrupt PNG (image data: {exc})") from None
    if len(raw) != height * (1 + 2 * width):
        raise DataError(f"{name}: corrupt PNG ({len(raw)} bytes of image data for {width}x{height} 16-bit pixels)")
    rows = np.frombuffer(raw, dtype=np.uint8).reshape(height, 1 + 2 * width)
    filters = rows[:, 0]
    if np.any((filters != _NONE) & (filters != _SUB)):
        return None
    filtered = rows[:, 1:].reshape(height, width, 2)
    # Sub: each byte adds the byte two before it (the same byte of the pixel to the left), modulo 256.
    pixels = np.cumsum(filtered, axis=1, dtype=np.uint8)
    none = filters == _NONE
    if none.any():
        pixels[none] = filtered[none]
    return pixels.view(">u2")[:, :, 0]


def encode_gray16(pixels):
    """A PNG file's bytes of 16-bit grayscale pixels: every row Sub-filtered (each byte less the same byte of the
    pixel to its left, modulo 256), deflated by ISA-L at its fastest level; :func:`decode_gray16` reads it back.

    Parameters
    ----------
    pixels : array-like of uint16, shape (height, width)

    Returns
    -------
    data : bytes
    """
    pixels = np.asarray(pixels)
    if pixels.ndim != 2 or pixels.dtype.kind != "u" or pixels.dtype.itemsize != 2:
        raise ValueError(f"encode_gray16 takes a 2-D uint16 array, got {pixels.dtype} of shape {pixels.shape}")
    height, width = pixels.shape
    data = pixels.astype(">u2").view(np.uint8).reshape(height, width, 2)
    rows = np.empty((height, 1 + 2 * width), dtype=np.uint8)
    rows[:, 0] = _SUB
    filtered = rows[:, 1:].reshape(height, width, 2)
    filtered[:, 0] = data[:, 0]
    np.subtract(data[:, 1:], data[:, :-1], out=filtered[:, 1:])  # uint8: modulo 256
    header = struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0)
    return (_SIGNATURE + _chunk(b"IHDR", header) + _chunk(b"IDAT", isal_zlib.compress(rows.tobytes(), level=1))
            + _chunk(b"IEND", b""))


def _chunk(kind, body):
    """A PNG chunk: length, type, data and their CRC."""
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", _crc(kind, body))


def _crc(kind, body):
    """The CRC-32 of a chunk's type and data, as PNG stores it after them."""
    return isal_zlib.crc32(body, isal_zlib.crc32(kind))
