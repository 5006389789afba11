"""Error types shared by :mod:`hdrjax.layers` and :mod:`hdrjax.io`.

Every problem with a file's content (truncated data, wrong magic number, corrupt
run-length encoding, absurd dimensions, an unknown pixel type, a layer whose shape
disagrees with the image, a layer that is not there) raises :class:`ReadError` or a
subclass, with a one-line message that starts with the file name.
"""


class ReadError(ValueError):
    """A file (or an in-memory layered image) is malformed, corrupt or unsupported.

    The message is one line naming the file and what was expected, e.g.
    ``"x.hdr: not a Radiance file (missing '#?RADIANCE' or '#?RGBE' header)"``.
    """


class MissingLayerError(ReadError):
    """A named layer (or part, or view) was asked for and is not in the file.

    Example message: ``"Scene.exr has no 'position' layer; layers present: error, hits"``.
    """


class LayerShapeError(ReadError):
    """A layer's shape disagrees with the image (a grid layer must be ``(H, W)`` or
    ``(H, W, k)`` for an ``(H, W, C)`` image)."""


__all__ = ["LayerShapeError", "MissingLayerError", "ReadError"]
