"""Numbers as text, by compiled loops: exact float64 formatting and parsing.

Text mesh formats (3MF above all) hold millions of numbers. Formatting them
with Python's ``%r`` and parsing them with ``float`` costs about a
microsecond each; the loops here do the same work in compiled code
(:mod:`geotex.jit`) and give the same results, bit for bit:

* :func:`format_rows` writes each float64 as Python's ``repr`` does (the
  shortest decimal that reads back to the same float64, nearest to it among
  the shortest, in ``repr``'s layout: ``0.5``, ``2.0``, ``1e-05``), and each
  integer as ``%d`` does. Digits come from exact 128-bit integer arithmetic
  (the value times a power of ten, correctly rounded to 15, 16 or 17
  significant digits; the shortest that reads back is kept). Values outside
  ``1e-11 <= |x| < 1e14`` (and zeros, infinities, NaN) are formatted by
  ``repr`` itself.
  Below :data:`geotex.jit.JIT_MIN_SIZE` values Python formats them (same
  bytes; loading numba would cost more than it saves).
* :func:`parse_floats` and :func:`parse_ints` read the quoted tokens of a
  byte string. A float token ``[+-]digits[.digits][(e|E)[+-]digits]`` of at
  most 19 significant digits is converted with a correctly rounded algorithm
  (Clinger's fast path when it applies, else an estimate corrected by an
  exact 128-bit comparison with the half-way points); every other token is
  left to numpy's own conversion (the caller's fallback), so what is
  accepted and what each token means never change.

Correct rounding makes the results equal to Python's ``float`` and ``repr``
(tested on millions of random and float32-exact values).
"""

from __future__ import annotations

import math

import numpy as np

from geotex.errors import InputError
from geotex.jit import JIT_MIN_SIZE, compiled, helper

__all__ = ["format_rows", "parse_floats", "parse_ints", "quoted_spans"]

_POW5 = np.array([5 ** i for i in range(28)], dtype=np.uint64)
_POW10U = np.array([10 ** i for i in range(20)], dtype=np.uint64)
_POW10F = np.array([10.0 ** i for i in range(23)], dtype=np.float64)
#: Width of one formatted number (``repr`` of a float64 is at most 24 bytes).
_SLOT = 32


# --------------------------------------------------------------- 128-bit help
@helper
def _mul128(a, b):
    """``a * b`` for uint64 ``a``, ``b`` as ``(hi, lo)``."""
    m32 = np.uint64(0xFFFFFFFF)
    s32 = np.uint64(32)
    a_lo = a & m32
    a_hi = a >> s32
    b_lo = b & m32
    b_hi = b >> s32
    p0 = a_lo * b_lo
    p1 = a_lo * b_hi
    p2 = a_hi * b_lo
    p3 = a_hi * b_hi
    mid = (p0 >> s32) + (p1 & m32) + (p2 & m32)
    lo = (p0 & m32) | (mid << s32)
    hi = p3 + (p1 >> s32) + (p2 >> s32) + (mid >> s32)
    return hi, lo


@helper
def _shl128(hi, lo, s):
    """``(hi, lo) << s`` for ``0 <= s < 128`` (bits beyond 128 are lost)."""
    if s == 0:
        return hi, lo
    if s >= 64:
        return lo << np.uint64(s - 64), np.uint64(0)
    return (hi << np.uint64(s)) | (lo >> np.uint64(64 - s)), lo << np.uint64(s)


@helper
def _shr128(hi, lo, s):
    """``(hi, lo) >> s`` for ``0 <= s < 128``."""
    if s == 0:
        return hi, lo
    if s >= 64:
        return np.uint64(0), hi >> np.uint64(s - 64)
    return hi >> np.uint64(s), (lo >> np.uint64(s)) | (hi << np.uint64(64 - s))


@helper
def _sub128(ahi, alo, bhi, blo):
    """``a - b`` for ``a >= b``."""
    lo = alo - blo
    borrow = np.uint64(1) if alo < blo else np.uint64(0)
    return ahi - bhi - borrow, lo


@helper
def _less128(ahi, alo, bhi, blo):
    return ahi < bhi or (ahi == bhi and alo < blo)


@helper
def _bitlen(x):
    n = 0
    while x != np.uint64(0):
        x = x >> np.uint64(1)
        n += 1
    return n


@helper
def _side(D, p, M, E, pow5):
    """Where ``D * 10**-p`` lies from the float ``M * 2**E`` (``2**52 <= M < 2**53``).

    0 when it rounds (to nearest, ties to even) to that float, +1 when it
    rounds above it, -1 below; ``p`` in 0..27, exact 128-bit arithmetic.
    """
    g = E + p
    s = 2 - g
    h5 = pow5[p]
    r_hi, r_lo = _mul128(M, h5)
    if s >= 0:
        if _bitlen(D) + s > 127:
            return 2                        # far off (the caller never asks this)
        l_hi, l_lo = _shl128(np.uint64(0), D, s)
        r_hi, r_lo = _shl128(r_hi, r_lo, 2)
        up = 1
        down = 0
    else:
        l_hi, l_lo = np.uint64(0), D
        r_hi, r_lo = _shl128(r_hi, r_lo, 2 - s)
        up = 1 - s
        down = -s
    even = (M & np.uint64(1)) == np.uint64(0)
    if not _less128(l_hi, l_lo, r_hi, r_lo):          # at or above the float
        d_hi, d_lo = _sub128(l_hi, l_lo, r_hi, r_lo)
        h_hi, h_lo = _shl128(np.uint64(0), h5, up)
        if _less128(d_hi, d_lo, h_hi, h_lo):
            return 0
        if d_hi == h_hi and d_lo == h_lo and even:
            return 0
        return 1
    d_hi, d_lo = _sub128(r_hi, r_lo, l_hi, l_lo)
    # below a power of two the gap to the next smaller float is half as wide
    h_hi, h_lo = _shl128(np.uint64(0), h5, down if M == np.uint64(1 << 52) else up)
    if _less128(d_hi, d_lo, h_hi, h_lo):
        return 0
    if d_hi == h_hi and d_lo == h_lo and even:
        return 0
    return -1


# --------------------------------------------------------------- formatting
@helper
def _digits_at(M, E, k, pow5):
    """``round(M * 2**E * 10**k)`` (ties to even), ``0 <= k <= 27``, as uint64."""
    p_hi, p_lo = _mul128(M, pow5[k])
    s = E + k
    if s >= 0:
        p_hi, p_lo = _shl128(p_hi, p_lo, s)
        return p_lo
    t = -s
    if t >= 128:
        return np.uint64(0)
    q2_hi, q2_lo = _shr128(p_hi, p_lo, t - 1)
    back_hi, back_lo = _shl128(q2_hi, q2_lo, t - 1)
    sticky = back_hi != p_hi or back_lo != p_lo
    half = (q2_lo & np.uint64(1)) == np.uint64(1)
    q_hi, q_lo = _shr128(q2_hi, q2_lo, 1)
    if half and (sticky or (q_lo & np.uint64(1)) == np.uint64(1)):
        q_lo += np.uint64(1)
    return q_lo


@helper
def _put_uint(out, at, value, width):
    """Write ``width`` decimal digits of ``value`` at ``out[at:]``."""
    for i in range(width - 1, -1, -1):
        out[at + i] = 48 + np.int64(value % np.uint64(10))
        value = value // np.uint64(10)
    return at + width


@helper
def _format_float(bits, x, out, at, pow5, pow10u):
    """Write ``repr(x)`` at ``out[at:]``; return the end, or -1 if out of range."""
    ax = abs(x)
    if not (ax >= 1e-11 and ax < 1e14):
        return -1
    M = (bits & np.uint64((1 << 52) - 1)) | np.uint64(1 << 52)
    E = np.int64((bits >> np.uint64(52)) & np.uint64(0x7FF)) - 1075
    d = np.int64(math.floor(math.log10(ax)))
    # exact decimal exponent: 10**d <= x < 10**(d+1), checked at 17 digits
    for _ in range(3):
        if d < -11 or d > 13:
            return -1
        N = _digits_at(M, E, 16 - d, pow5)
        if N >= pow10u[17]:
            d += 1
        elif N < pow10u[16]:
            d -= 1
        else:
            break
    digits = np.uint64(0)
    nd = 0
    dd = d
    for n in range(15, 18):
        k = n - 1 - d
        if k > 27:
            return -1
        N = _digits_at(M, E, k, pow5)
        if n == 17 or _side(N, k, M, E, pow5) == 0:
            dd = d
            if N == pow10u[n]:                  # rounded up to the next power of ten
                N = pow10u[n - 1]
                dd = d + 1
            digits = N
            nd = n
            break
    while nd > 1 and digits % np.uint64(10) == np.uint64(0):
        digits = digits // np.uint64(10)
        nd -= 1
    if x < 0:
        out[at] = 45                             # '-'
        at += 1
    if dd >= 16 or dd < -4:                      # 1.2345e-05 (never 1e16 here)
        lead = digits // pow10u[nd - 1]
        out[at] = 48 + np.int64(lead)
        at += 1
        if nd > 1:
            out[at] = 46                         # '.'
            at = _put_uint(out, at + 1, digits - lead * pow10u[nd - 1], nd - 1)
        out[at] = 101                            # 'e'
        out[at + 1] = 45 if dd < 0 else 43
        at = _put_uint(out, at + 2, np.uint64(abs(dd)), 2)
        return at
    if dd >= 0:
        if nd <= dd + 1:                         # integer: digits, zeros, '.0'
            at = _put_uint(out, at, digits, nd)
            for _ in range(dd + 1 - nd):
                out[at] = 48
                at += 1
            out[at] = 46
            out[at + 1] = 48
            return at + 2
        scale = pow10u[nd - dd - 1]
        at = _put_uint(out, at, digits // scale, dd + 1)
        out[at] = 46
        return _put_uint(out, at + 1, digits % scale, nd - dd - 1)
    out[at] = 48
    out[at + 1] = 46
    at += 2
    for _ in range(-dd - 1):
        out[at] = 48
        at += 1
    return _put_uint(out, at, digits, nd)


@compiled
def _format_float_slots(bits, values, slots, lengths, pow5, pow10u):
    """Each value's ``repr`` into its row of ``slots``; length 0 = not done."""
    for i in range(values.shape[0]):
        end = _format_float(bits[i], values[i], slots[i], 0, pow5, pow10u)
        lengths[i] = end if end > 0 else 0


@compiled
def _format_int_slots(values, slots, lengths, pow10u):
    for i in range(values.shape[0]):
        v = values[i]
        at = 0
        if v < 0:
            slots[i, 0] = 45
            at = 1
            if v == -9223372036854775807 - 1:
                lengths[i] = 0                   # left to Python
                continue
            v = -v
        u = np.uint64(v)
        n = 1
        while n < 19 and u >= pow10u[n]:
            n += 1
        lengths[i] = _put_uint(slots[i], at, u, n)


@compiled
def _assemble(slots, lengths, k, template, cuts, out):
    """Rows ``piece0 v0 piece1 v1 ... piece_k`` into ``out``; returns the length."""
    at = 0
    n = lengths.shape[0] // k
    for r in range(n):
        for j in range(k + 1):
            for c in range(cuts[j], cuts[j + 1]):
                out[at] = template[c]
                at += 1
            if j < k:
                i = r * k + j
                for c in range(lengths[i]):
                    out[at] = slots[i, c]
                    at += 1
    return at


def format_rows(pieces: tuple[str, ...], values: np.ndarray, *,
                compiled: bool | None = None) -> bytes:
    """Rows ``pieces[0] v0 pieces[1] v1 ... pieces[k]`` for each row of ``values``.

    Parameters
    ----------
    pieces : tuple of str
        ``k + 1`` ASCII texts around the ``k`` numbers of a row.
    values : numpy.ndarray, (n, k) float64 or integer
        Floats are written as ``repr`` writes them, integers as ``%d``.
    compiled : bool, optional
        Use the compiled loops (True) or Python's ``%`` (False); by default
        the compiled loops from :data:`geotex.jit.JIT_MIN_SIZE` values up.

    Returns
    -------
    bytes
        The same bytes as ``"".join(pieces[0] + ... for each row).encode()``
        with ``%r`` / ``%d`` formatting.

    Raises
    ------
    InputError
        If ``len(pieces) != values.shape[1] + 1``.

    Notes
    -----
    Below :data:`geotex.jit.JIT_MIN_SIZE` values the rows are formatted by
    Python's ``%`` operator (loading numba would cost more); the bytes are
    the same.
    """
    values = np.asarray(values)
    n = values.shape[0]
    k = values.shape[1] if values.ndim == 2 else 0
    if values.ndim != 2 or len(pieces) != k + 1:
        raise InputError(f"format_rows: {len(pieces)} pieces for rows of {k} values")
    if n == 0:
        return b""
    is_float = np.issubdtype(values.dtype, np.floating)
    if not (values.size >= JIT_MIN_SIZE if compiled is None else compiled):
        code = "%r" if is_float else "%d"
        row = code.join(p.replace("%", "%%") for p in pieces)
        flat = values.astype(np.float64 if is_float else np.int64).ravel().tolist()
        return ((row * n) % tuple(flat)).encode("ascii")
    template_bytes = "".join(pieces).encode("ascii")
    template = np.frombuffer(template_bytes, dtype=np.uint8)
    cuts = np.cumsum([0] + [len(p) for p in pieces]).astype(np.int64)
    flat = np.ascontiguousarray(values).reshape(-1)
    slots = np.empty((flat.shape[0], _SLOT if is_float else 24), dtype=np.uint8)
    lengths = np.zeros(flat.shape[0], dtype=np.int64)
    if is_float:
        flat = flat.astype(np.float64, copy=False)
        _format_float_slots(flat.view(np.uint64), flat, slots, lengths, _POW5, _POW10U)
        text = repr
    else:
        flat = flat.astype(np.int64, copy=False)
        _format_int_slots(flat, slots, lengths, _POW10U)
        text = str
    for i in np.flatnonzero(lengths == 0).tolist():     # zeros, huge, tiny, inf, nan
        t = text(float(flat[i]) if is_float else int(flat[i])).encode("ascii")
        slots[i, :len(t)] = np.frombuffer(t, dtype=np.uint8)
        lengths[i] = len(t)
    out = np.empty(int(lengths.sum()) + n * len(template_bytes), dtype=np.uint8)
    end = _assemble(slots, lengths, k, template, cuts, out)
    return out[:end].tobytes()


# --------------------------------------------------------------- parsing
@compiled
def _same_separators(body, quotes, seps_same, period):
    """Compare every separator between quoted values with the first of its class."""
    n_sep = quotes.shape[0] // 2 - 1
    for i in range(n_sep):
        cls = i % period
        first_a = quotes[2 * cls + 1] + 1
        first_b = quotes[2 * cls + 2]
        a = quotes[2 * i + 1] + 1
        b = quotes[2 * i + 2]
        if b - a != first_b - first_a:
            seps_same[cls] = False
            continue
        for c in range(b - a):
            if body[a + c] != body[first_a + c]:
                seps_same[cls] = False
                break


def quoted_spans(body: bytes, quote: bytes, period: int):
    """Quoted values of ``body`` and its separators, if uniform.

    Parameters
    ----------
    body : bytes
    quote : bytes
        The quote character (one byte).
    period : int
        Values per row: separators ``i`` and ``i + period`` must be equal.

    Returns
    -------
    quotes : numpy.ndarray, (2t,) int64
        Positions of the quote characters (value ``i`` lies between
        ``quotes[2i] + 1`` and ``quotes[2i + 1]``).
    separators : list of bytes or None
        The ``period`` distinct separator texts (after value 0, 1, ...), or
        None when the separators of a class differ (or there are too few).
    """
    arr = np.frombuffer(body, dtype=np.uint8)
    quotes = np.flatnonzero(arr == quote[0]).astype(np.int64)
    if quotes.shape[0] < 2 * period + 2 or quotes.shape[0] % 2:
        return quotes, None
    same = np.ones(period, dtype=bool)
    _same_separators(arr, quotes, same, period)
    if not same.all():
        return quotes, None
    return quotes, [body[quotes[2 * c + 1] + 1:quotes[2 * c + 2]] for c in range(period)]


@helper
def _parse_float(body, a, b, pow5, pow10f, scratch):
    """Correctly rounded value of ``body[a:b]``; ``(value, ok)``, ok False = not handled."""
    i = a
    neg = False
    if i < b and (body[i] == 45 or body[i] == 43):
        neg = body[i] == 45
        i += 1
    D = np.uint64(0)
    nsig = 0
    ndig = 0
    drop = 0                    # digits after the point
    seen_point = False
    while i < b:
        c = body[i]
        if 48 <= c <= 57:
            ndig += 1
            if nsig > 0 or c != 48:
                if nsig >= 19:
                    return 0.0, False
                D = D * np.uint64(10) + np.uint64(c - 48)
                nsig += 1
            if seen_point:
                drop += 1
        elif c == 46 and not seen_point:
            seen_point = True
        else:
            break
        i += 1
    if ndig == 0:
        return 0.0, False
    e10 = 0
    if i < b and (body[i] == 101 or body[i] == 69):
        i += 1
        eneg = False
        if i < b and (body[i] == 45 or body[i] == 43):
            eneg = body[i] == 45
            i += 1
        ne = 0
        while i < b and 48 <= body[i] <= 57:
            if e10 < 100000:
                e10 = e10 * 10 + (body[i] - 48)
            ne += 1
            i += 1
        if ne == 0:
            return 0.0, False
        if eneg:
            e10 = -e10
    if i != b:
        return 0.0, False
    q = e10 - drop
    if D == np.uint64(0):
        return (-0.0 if neg else 0.0), True
    if D <= np.uint64(1 << 53) and -22 <= q <= 22:      # Clinger: one rounding
        v = np.float64(D)
        v = v * pow10f[q] if q >= 0 else v / pow10f[-q]
        return (-v if neg else v), True
    if q > 0 or q < -27:
        return 0.0, False
    p = -q
    v = np.float64(D) / pow10f[min(p, 22)]
    if p > 22:
        v = v / pow10f[p - 22]
    if not (v >= 2.2250738585072014e-308 and v < 1.7976931348623157e308):
        return 0.0, False
    scratch[0] = v
    bits = scratch.view(np.uint64)[0]
    M = (bits & np.uint64((1 << 52) - 1)) | np.uint64(1 << 52)
    E = np.int64((bits >> np.uint64(52)) & np.uint64(0x7FF)) - 1075
    for _ in range(8):
        side = _side(D, p, M, E, pow5)
        if side == 0:
            bits = (np.uint64(E + 1075) << np.uint64(52)) | (M - np.uint64(1 << 52))
            scratch.view(np.uint64)[0] = bits
            v = scratch[0]
            return (-v if neg else v), True
        if side == 2:
            return 0.0, False
        if side > 0:
            M += np.uint64(1)
            if M == np.uint64(1 << 53):
                M = np.uint64(1 << 52)
                E += 1
        else:
            M -= np.uint64(1)
            if M < np.uint64(1 << 52):
                M = np.uint64((1 << 53) - 1)
                E -= 1
    return 0.0, False


@compiled
def _parse_float_spans(body, starts, ends, out, ok, pow5, pow10f):
    scratch = np.empty(1, dtype=np.float64)
    for t in range(starts.shape[0]):
        v, good = _parse_float(body, starts[t], ends[t], pow5, pow10f, scratch)
        out[t] = v
        ok[t] = good


@compiled
def _parse_int_spans(body, starts, ends, out, ok):
    for t in range(starts.shape[0]):
        a = starts[t]
        b = ends[t]
        good = b > a and b - a <= 18
        v = 0
        for i in range(a, b):
            c = body[i]
            if c < 48 or c > 57:
                good = False
                break
            v = v * 10 + (c - 48)
        out[t] = v if good else 0
        ok[t] = good


def parse_floats(body: bytes, starts: np.ndarray, ends: np.ndarray):
    """Values of the tokens ``body[starts[i]:ends[i]]`` read as float64.

    Returns
    -------
    values : numpy.ndarray, (t,) float64
    handled : numpy.ndarray, (t,) bool
        False where the token is outside the compiled grammar or range; its
        value is then 0 and the caller converts it itself.
    """
    arr = np.frombuffer(body, dtype=np.uint8)
    out = np.empty(starts.shape[0], dtype=np.float64)
    ok = np.empty(starts.shape[0], dtype=bool)
    _parse_float_spans(arr, starts.astype(np.int64), ends.astype(np.int64), out, ok,
                       _POW5, _POW10F)
    return out, ok


def parse_ints(body: bytes, starts: np.ndarray, ends: np.ndarray):
    """Values of the tokens ``body[starts[i]:ends[i]]`` made only of 1-18 digits.

    Returns
    -------
    values : numpy.ndarray, (t,) int64
    handled : numpy.ndarray, (t,) bool
        False for any other token (value 0; the caller converts it itself).
    """
    arr = np.frombuffer(body, dtype=np.uint8)
    out = np.empty(starts.shape[0], dtype=np.int64)
    ok = np.empty(starts.shape[0], dtype=bool)
    _parse_int_spans(arr, starts.astype(np.int64), ends.astype(np.int64), out, ok)
    return out, ok
