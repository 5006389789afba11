"""Operators with a time course: adaptation carried from frame to frame.

A time-dependent operator maps a still image as an observer fully adapted to it (its
``__call__``) and declares, with :meth:`AbstractTimeDependentOperator.sequence`, how the
observer's state evolves over a sequence of frames shown at a frame rate. Batch rendering
(``hdrjax batch --fps``) reads that declaration and carries the state from frame to frame
and from one compiled chunk of frames to the next; nothing outside the operator knows its
model.

The shared mechanics live here: argument checking (:func:`sequence_arguments`) and the
``jax.lax.scan`` over frames (:func:`scan_frames`): the observer starts adapted to the
first frame (its state built from that frame) unless an initial state is given, in which
case it adapts for one frame interval before the first frame too; before each later frame
it adapts for ``1 / fps`` seconds to that frame, and the frame is mapped with the state
reached. Mapping a sequence in chunks, each chunk starting from the state the previous one
ended with, therefore equals mapping it in one scan.
"""

import abc
from collections.abc import Callable
from typing import Any, TypeGuard

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, ArrayLike, Float

from ._base import AbstractOperator, as_float_image, get_operator, operator_names


class AbstractTimeDependentOperator(AbstractOperator):
    """A tone-mapping operator with a time course (module docstring): its ``__call__`` maps
    a still image in the steady state, :meth:`sequence` maps frames with the model's
    dynamics."""

    @abc.abstractmethod
    def sequence(
        self,
        frames: Float[ArrayLike, "T H W 3"],
        fps: float,
        *,
        initial: Any = None,
    ) -> tuple[Float[Array, "T H W 3"], Any]:
        """Map frames shown at ``fps`` frames per second, in order.

        Args:
            frames: ``(T, H, W, 3)`` linear RGB, as ``__call__`` takes one image.
            fps: frames per second.
            initial: the observer's state before the first frame (a state this method
                returned, e.g. the last of a previous chunk); ``None``: adapted to the
                first frame.

        Returns:
            The mapped frames and the state after each frame (a pytree whose leaves have a
            leading ``T`` axis; the last one carries on to the next frames).
        """


def time_dependent_names() -> tuple[str, ...]:
    """Registered operators that declare a time course (:class:`AbstractTimeDependentOperator`)."""
    return tuple(
        n for n in operator_names() if issubclass(get_operator(n), AbstractTimeDependentOperator)
    )


def has_time_course(op: AbstractOperator) -> TypeGuard[AbstractTimeDependentOperator]:
    """Whether ``op`` declares a time course (``hdrjax batch --fps`` can run it)."""
    return isinstance(op, AbstractTimeDependentOperator)


def sequence_arguments(frames: ArrayLike, fps: Any) -> tuple[Array, Array]:
    """Checked ``frames`` (``(T, H, W, 3)``, promoted to float) and the frame interval
    ``1 / fps`` in seconds, in the frames' dtype."""
    frames = as_float_image(frames, "frames")
    if frames.ndim != 4:
        raise ValueError(f"frames: expected (T, H, W, 3), got shape {frames.shape}")
    if not isinstance(fps, jax.core.Tracer) and not bool(np.all(np.asarray(fps) > 0)):
        raise ValueError(f"fps: expected frames per second > 0, got {fps!r}")
    return frames, 1.0 / jnp.asarray(fps, frames.dtype)


def scan_frames(
    adapt: Callable[[Any, Any], Any],
    render: Callable[[Any, Any], Array],
    initial: Any,
    xs: Any,
    adapted_to_first: bool,
) -> tuple[Array, Any]:
    """``jax.lax.scan`` of the module docstring's time course.

    Args:
        adapt: ``adapt(state, x)``: the state one frame interval later under frame ``x``.
        render: ``render(state, x)``: frame ``x`` mapped for the observer ``state``.
        initial: the state before the first frame.
        xs: per-frame inputs (a pytree with a leading frame axis).
        adapted_to_first: ``initial`` is already adapted to the first frame (built from
            it): the first frame is mapped with it as it is; otherwise it adapts first.

    Returns:
        The mapped frames and the state after each frame (leading frame axis).
    """
    n = jax.tree.leaves(xs)[0].shape[0]
    moves = jnp.arange(n) >= (1 if adapted_to_first else 0)

    def body(state, inputs):
        x, move = inputs
        moved = adapt(state, x)
        state = jax.tree.map(lambda a, b: jnp.where(move, a, b), moved, state)
        return state, (render(state, x), state)

    _, (out, states) = jax.lax.scan(body, initial, (xs, moves))
    return out, states


__all__ = [
    "AbstractTimeDependentOperator",
    "has_time_course",
    "scan_frames",
    "sequence_arguments",
    "time_dependent_names",
]
