"""A silent structural check of an OpenEXR file through the OpenEXRCore C API.

The ``OpenEXR`` Python bindings report a corrupt file by printing: the C library's default
error handler writes to the process's standard error, and the bindings print a warning on
``sys.stdout`` and return fewer parts than the file has. Redirecting the output around a
read is process-wide (other threads' output is lost), so this module asks the same C
library (its functions are exported by the bindings' extension module) the questions the
bindings will ask, with an error handler of our own that collects the messages:

- the header parses (``exr_start_read``);
- every chunk of every part's top level has a readable leader inside the file
  (``exr_read_scanline_chunk_info`` / ``exr_read_tile_chunk_info``): this catches
  truncated files and corrupt offset tables, the common failures.

A file that passes is then read by the bindings; what is left for them to find is
compressed data that does not decode (the framing being intact), which the library still
prints. Where the C functions cannot be found (another build of the bindings), the check
is skipped and the bindings report as they do.
"""

import ctypes
import threading

_ERRFUNC = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int32, ctypes.c_char_p)


class _Initializer(ctypes.Structure):
    # exr_context_initializer_t as of OpenEXR 3.2 (``size`` versions the layout)
    _fields_ = [
        ("size", ctypes.c_size_t),
        ("error_handler_fn", _ERRFUNC),
        ("alloc_fn", ctypes.c_void_p),
        ("free_fn", ctypes.c_void_p),
        ("user_data", ctypes.c_void_p),
        ("read_fn", ctypes.c_void_p),
        ("size_fn", ctypes.c_void_p),
        ("write_fn", ctypes.c_void_p),
        ("destroy_fn", ctypes.c_void_p),
        ("max_image_width", ctypes.c_int),
        ("max_image_height", ctypes.c_int),
        ("max_tile_width", ctypes.c_int),
        ("max_tile_height", ctypes.c_int),
        ("zip_level", ctypes.c_int),
        ("dwa_quality", ctypes.c_float),
        ("flags", ctypes.c_int),
        ("pad", ctypes.c_uint8 * 4),
    ]


class _ChunkInfo(ctypes.Structure):
    # exr_chunk_info_t, with room to spare should a later version grow it
    _fields_ = [
        ("idx", ctypes.c_int32),
        ("start_x", ctypes.c_int32),
        ("start_y", ctypes.c_int32),
        ("height", ctypes.c_int32),
        ("width", ctypes.c_int32),
        ("level_x", ctypes.c_uint8),
        ("level_y", ctypes.c_uint8),
        ("type", ctypes.c_uint8),
        ("compression", ctypes.c_uint8),
        ("data_offset", ctypes.c_uint64),
        ("packed_size", ctypes.c_uint64),
        ("unpacked_size", ctypes.c_uint64),
        ("sample_count_data_offset", ctypes.c_uint64),
        ("sample_count_table_size", ctypes.c_uint64),
        ("spare", ctypes.c_uint8 * 64),
    ]


_SCANLINE, _TILED = 0, 1
_lib = None
_lock = threading.Lock()


def _core():
    """The OpenEXRCore functions of the loaded bindings, or ``False`` when not exported."""
    global _lib
    with _lock:
        if _lib is None:
            try:
                import OpenEXR

                lib = ctypes.CDLL(OpenEXR.__file__)
                i, p = ctypes.c_int, ctypes.c_void_p
                for fn, args in {
                    "exr_start_read": [p, ctypes.c_char_p, p],
                    "exr_finish": [p],
                    "exr_get_count": [p, p],
                    "exr_get_storage": [p, i, p],
                    "exr_get_data_window": [p, i, p],
                    "exr_get_scanlines_per_chunk": [p, i, p],
                    "exr_get_chunk_count": [p, i, p],
                    "exr_get_tile_counts": [p, i, i, i, p, p],
                    "exr_read_scanline_chunk_info": [p, i, i, p],
                    "exr_read_tile_chunk_info": [p, i, i, i, i, i, p],
                }.items():
                    f = getattr(lib, fn)
                    f.argtypes, f.restype = args, ctypes.c_int
                lib.exr_get_error_code_as_string.argtypes = [ctypes.c_int]
                lib.exr_get_error_code_as_string.restype = ctypes.c_char_p
                _lib = lib
            except (ImportError, OSError, AttributeError):
                _lib = False
    return _lib


def check(path: str, size: int) -> str | None:
    """The first problem OpenEXRCore finds in the structure of the file ``path`` (``size``
    bytes), as one line (``"EXR_ERR_...: message"``); ``None`` when it finds none or the
    check is not available. Nothing is printed."""
    lib = _core()
    if not lib:
        return None
    messages: list[str] = []

    def on_error(_ctxt, code, msg):
        name = lib.exr_get_error_code_as_string(code) or b"EXR_ERR"
        text = (msg or b"").decode("utf-8", "replace").replace(path, "").strip(": ")
        messages.append(f"{name.decode('ascii', 'replace')}: {' '.join(text.split())}")

    handler = _ERRFUNC(on_error)  # kept alive until exr_finish below
    init = _Initializer(size=ctypes.sizeof(_Initializer), error_handler_fn=handler)
    init.zip_level, init.dwa_quality = -2, -1.0
    ctx = ctypes.c_void_p()

    def failed(rv: int, what: str) -> str:
        if messages:
            return messages[0]
        name = lib.exr_get_error_code_as_string(rv) or b"EXR_ERR"
        return f"{name.decode('ascii', 'replace')}: {what}"

    rv = lib.exr_start_read(ctypes.byref(ctx), path.encode(), ctypes.byref(init))
    try:
        if rv:
            return failed(rv, "unreadable header")
        return _check_chunks(lib, ctx, size, failed)
    finally:
        lib.exr_finish(ctypes.byref(ctx))


def _check_chunks(lib, ctx, size: int, failed) -> str | None:
    c_int = ctypes.c_int
    nparts, storage, lines, count = c_int(), c_int(), c_int(), c_int()
    if rv := lib.exr_get_count(ctx, ctypes.byref(nparts)):
        return failed(rv, "no part count")
    info = _ChunkInfo()
    for part in range(nparts.value):
        if rv := lib.exr_get_storage(ctx, part, ctypes.byref(storage)):
            return failed(rv, f"no storage type for part {part}")
        if rv := lib.exr_get_chunk_count(ctx, part, ctypes.byref(count)):
            return failed(rv, f"no chunk count for part {part}")
        # each chunk takes at least an 8-byte offset and an 8-byte leader: a count the
        # file cannot hold is refused before looping over it
        if count.value < 0 or 16 * count.value > size:
            return f"EXR_ERR_BAD_CHUNK_LEADER: part {part} claims {count.value} chunks"
        if storage.value == _SCANLINE:
            dw = (ctypes.c_int32 * 4)()
            if rv := lib.exr_get_data_window(ctx, part, dw):
                return failed(rv, f"no data window for part {part}")
            if rv := lib.exr_get_scanlines_per_chunk(ctx, part, ctypes.byref(lines)):
                return failed(rv, f"no scanlines per chunk for part {part}")
            for y in range(dw[1], dw[3] + 1, max(lines.value, 1)):
                if rv := lib.exr_read_scanline_chunk_info(ctx, part, y, ctypes.byref(info)):
                    return failed(rv, f"unreadable chunk at scanline {y} of part {part}")
        elif storage.value == _TILED:
            nx, ny = c_int(), c_int()
            if rv := lib.exr_get_tile_counts(ctx, part, 0, 0, ctypes.byref(nx), ctypes.byref(ny)):
                return failed(rv, f"no tile counts for part {part}")
            for ty in range(ny.value):
                for tx in range(nx.value):
                    rv = lib.exr_read_tile_chunk_info(ctx, part, tx, ty, 0, 0, ctypes.byref(info))
                    if rv:
                        return failed(rv, f"unreadable tile ({tx}, {ty}) of part {part}")
    return None
