"""Decompression of LZ-String's ``compressToBase64`` output (the format of the leapjs-playback recordings).

LZ-String (pieroxy) is an LZW variant: a stream of variable-width codes, each read least significant bit
first, where the code width grows by one bit whenever the dictionary outgrows it. Codes 0 and 1 introduce a
new 8- or 16-bit character, code 2 ends the stream, larger codes name dictionary entries. ``compressToBase64``
packs the bit stream six bits per character (most significant bit first) with the usual Base64 alphabet.

Written for handsim with numpy only: the bit stream is unpacked once, and every code is then read from a
precomputed window of the next 32 bits, so a 1 MB recording decodes in about a second.
"""
from __future__ import annotations

import numpy as np

_ALPHABET = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/"
_WINDOW = 32


class LZStringError(ValueError):
    """The text is not LZ-String compressToBase64 output (or it is truncated)."""


def decompress_from_base64(text: str, argument: str = "text") -> str:
    """The string that ``LZString.compressToBase64`` turned into `text`. Raises LZStringError naming
    `argument` when `text` is not such output."""
    if not isinstance(text, str):
        raise TypeError(f"{argument}: expected str, got {type(text).__name__}")
    text = text.strip().rstrip("=")
    if not text:
        return ""
    lookup = np.full(128, 255, np.uint8)
    lookup[np.frombuffer(_ALPHABET.encode(), np.uint8)] = np.arange(64, dtype=np.uint8)
    raw = np.frombuffer(text.encode("ascii", errors="replace"), np.uint8)
    if raw.max() >= 128 or (lookup[raw] == 255).any():
        bad = next(i for i, ch in enumerate(text) if ch not in _ALPHABET)
        raise LZStringError(f"{argument}: not Base64 LZ-String data (character {text[bad]!r} at {bad})")
    sextets = lookup[raw]
    bits = ((sextets[:, None] >> np.arange(5, -1, -1, dtype=np.uint8)) & 1).reshape(-1).astype(np.int64)
    nbits = bits.size
    padded = np.concatenate([bits, np.zeros(_WINDOW, np.int64)])
    # window[p] = the 32 bits starting at p, bit p as the least significant one
    window = np.zeros(nbits, np.int64)
    for k in range(_WINDOW):
        window |= padded[k:k + nbits] << k
    window = memoryview(window)  # indexing gives plain ints, much faster than numpy scalars

    pos = 0

    def read(n):
        nonlocal pos
        if pos + n > nbits:
            raise LZStringError(f"{argument}: LZ-String data ends in the middle of a code (truncated?)")
        value = window[pos] & ((1 << n) - 1)
        pos += n
        return value

    first = read(2)
    if first == 2:
        return ""
    if first not in (0, 1):
        raise LZStringError(f"{argument}: not LZ-String data (first code {first})")
    w = chr(read(8 if first == 0 else 16))
    dictionary = ["\x00", "\x01", "\x02", w]  # codes 0..2 are control codes
    result = [w]
    num_bits, enlarge_in = 3, 4
    mask = (1 << num_bits) - 1
    while True:
        # read(num_bits), inlined: this loop runs once per code
        if pos + num_bits > nbits:
            read(num_bits)  # raises the truncation error
        code = window[pos] & mask
        pos += num_bits
        if code < 2:
            dictionary.append(chr(read(8 if code == 0 else 16)))
            code = len(dictionary) - 1
            enlarge_in -= 1
        elif code == 2:
            return "".join(result)
        if enlarge_in == 0:
            enlarge_in = 1 << num_bits
            num_bits += 1
            mask = (1 << num_bits) - 1
        if 2 < code < len(dictionary):
            entry = dictionary[code]
        elif code == len(dictionary):
            entry = w + w[0]
        else:
            raise LZStringError(f"{argument}: not LZ-String data (code {code} with {len(dictionary)} entries)")
        result.append(entry)
        dictionary.append(w + entry[0])
        enlarge_in -= 1
        w = entry
        if enlarge_in == 0:
            enlarge_in = 1 << num_bits
            num_bits += 1
            mask = (1 << num_bits) - 1
