"""The fast 16-bit PNG reader and writer (``dgmm.odometry.depth_png``) against PIL, on TUM's own frames and on PNGs
built here byte by byte (row filters chosen, chunks and CRCs written with zlib), and the reader's errors."""
import io
import struct
import zlib

import numpy as np
import pytest
from PIL import Image

from conftest import SHARED_DATA
from dgmm.errors import DataError
from dgmm.odometry.depth_png import decode_gray16, encode_gray16
from dgmm.odometry.tum import DEPTH_SCALE, read_depth

FR1_DEPTH = SHARED_DATA / "tum" / "rgbd_dataset_freiburg1_xyz" / "depth"


def chunk(kind, body):
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))


def png(pixels, filters, bit_depth=16, header_width=None):
    """A grayscale PNG of ``pixels`` (uint16, or uint8 with ``bit_depth=8``) whose row ``r`` is filtered by
    ``filters[r]``: 0 (None), 1 (Sub: each byte less the one a pixel to its left, modulo 256) or 2 (Up: less the
    byte above); its header says ``header_width`` (default: the pixels' width)."""
    data = pixels.astype(">u2" if bit_depth == 16 else np.uint8).view(np.uint8).reshape(len(pixels), -1)
    step = bit_depth // 8
    rows = []
    for r, kind in enumerate(filters):
        row = data[r].astype(np.int64)
        if kind == 1:
            row = row - np.concatenate([np.zeros(step, dtype=np.int64), row[:-step]])
        elif kind == 2:
            row = row - (data[r - 1] if r else 0)
        rows.append(bytes([kind]) + (row % 256).astype(np.uint8).tobytes())
    header = struct.pack(">IIBBBBB", header_width or pixels.shape[1], pixels.shape[0], bit_depth, 0, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"".join(rows)))
            + chunk(b"IEND", b""))


def pil_pixels(path):
    with Image.open(path) as image:
        return np.asarray(image)


@pytest.mark.parametrize("index", [0, 397, 797])
def test_tum_frames_decode_as_pil_decodes_them(index):
    path = sorted(FR1_DEPTH.glob("*.png"))[index]
    pixels = decode_gray16(path.read_bytes())
    assert pixels is not None and pixels.shape == (480, 640)  # TUM's frames take the fast path
    np.testing.assert_array_equal(pixels, pil_pixels(path))
    np.testing.assert_array_equal(read_depth(path), pil_pixels(path) / DEPTH_SCALE)


def test_none_and_sub_rows_with_carries_across_bytes(tmp_path):
    """Random 16-bit pixels, so that the low bytes' Sub differences wrap around 256 (a decoder that adds 16-bit
    words, carrying into the high byte, or that sums along the wrong axis fails); None and Sub rows mixed. PIL reads
    the same file as a check on the encoder above."""
    pixels = np.random.default_rng(0).integers(0, 65536, size=(7, 9)).astype(np.uint16)
    (tmp_path / "mixed.png").write_bytes(png(pixels, [1, 0, 1, 1, 0, 0, 1]))
    np.testing.assert_array_equal(pil_pixels(tmp_path / "mixed.png"), pixels)
    np.testing.assert_array_equal(decode_gray16((tmp_path / "mixed.png").read_bytes()), pixels)


def test_other_pngs_are_left_to_pil(tmp_path):
    """Up rows, 8-bit pixels: not the fast path's (None), and read_depth decodes them through PIL, as PIL's own
    adaptive filters are."""
    pixels = np.random.default_rng(1).integers(0, 65536, size=(6, 5)).astype(np.uint16)
    assert decode_gray16(png(pixels, [1, 2, 1, 1, 1, 1])) is None
    (tmp_path / "up.png").write_bytes(png(pixels, [1, 2, 1, 1, 1, 1]))
    np.testing.assert_array_equal(read_depth(tmp_path / "up.png"), pixels / DEPTH_SCALE)
    assert decode_gray16(png(pixels.astype(np.uint8), [1] * 6, bit_depth=8)) is None
    smooth = np.add.outer(np.arange(48), np.arange(64)).astype(np.uint16) * 700  # PIL writes Up and Paeth rows
    Image.fromarray(smooth).save(tmp_path / "pil.png")
    assert decode_gray16((tmp_path / "pil.png").read_bytes()) is None
    np.testing.assert_array_equal(read_depth(tmp_path / "pil.png"), smooth / DEPTH_SCALE)


def test_written_depth_is_read_back_by_pil_and_fast():
    """encode_gray16 (write_depth's) of random 16-bit pixels: PIL, an independent decoder, reads the same pixels,
    and so does decode_gray16 (its fast path: the rows are Sub-filtered)."""
    pixels = np.random.default_rng(3).integers(0, 65536, size=(9, 11)).astype(np.uint16)
    data = encode_gray16(pixels)
    with Image.open(io.BytesIO(data)) as image:
        assert image.mode == "I;16"
        np.testing.assert_array_equal(np.asarray(image), pixels)
    np.testing.assert_array_equal(decode_gray16(data), pixels)


def test_corrupt_pngs_are_data_errors_naming_the_file(tmp_path):
    pixels = np.arange(20, dtype=np.uint16).reshape(4, 5) * 3000
    good = png(pixels, [1] * 4)
    idat = good.index(b"IDAT")
    flipped = bytearray(good)
    flipped[idat + 6] ^= 0xFF  # a byte of the compressed data: the chunk's CRC no longer matches
    cases = {"crc.png": (bytes(flipped), "CRC does not match"), "cut.png": (good[:idat + 10], "truncated"),
             "short.png": (png(pixels, [1] * 4, header_width=6), "44 bytes of image data for 6x4")}
    for name, (data, match) in cases.items():
        (tmp_path / name).write_bytes(data)
        with pytest.raises(DataError, match=f"{name}: corrupt PNG .*{match}"):
            read_depth(tmp_path / name)
