"""Box spaces for the RL environments, without Gymnasium.

When Gymnasium is importable the environments use its ``gymnasium.spaces.Box``; otherwise this ``Box``,
which offers what an agent needs of one: ``shape``, ``dtype``, ``low``/``high``, ``sample()``,
``contains()`` and ``seed()``.
"""

import numpy as np

try:  # Gymnasium is optional (it is not a Debian package)
    import gymnasium as _gymnasium
except ImportError:  # pragma: no cover - depends on the machine
    _gymnasium = None


class Box:
    """A box in R^n (or an image: integer dtype), [low, high] per element."""

    def __init__(self, low, high, shape=None, dtype=np.float32, seed=None):
        self.dtype = np.dtype(dtype)
        if shape is None:
            shape = np.shape(low)
        self.shape = tuple(int(n) for n in shape)
        self.low = np.broadcast_to(np.asarray(low, dtype=self.dtype), self.shape).copy()
        self.high = np.broadcast_to(np.asarray(high, dtype=self.dtype), self.shape).copy()
        if np.any(self.low > self.high):
            raise ValueError("Box: low must be <= high")
        self._rng = np.random.default_rng(seed)

    def seed(self, seed=None):
        self._rng = np.random.default_rng(seed)
        return [seed]

    def sample(self):
        """A uniform sample (bounded dimensions; unbounded ones are drawn from a unit normal)."""
        if np.issubdtype(self.dtype, np.integer):
            return self._rng.integers(self.low, self.high, size=self.shape, endpoint=True).astype(self.dtype)
        low = np.where(np.isfinite(self.low), self.low, -1.0)
        high = np.where(np.isfinite(self.high), self.high, 1.0)
        x = self._rng.uniform(low, high, size=self.shape)
        unbounded = ~(np.isfinite(self.low) & np.isfinite(self.high))
        x[unbounded] = self._rng.standard_normal(np.count_nonzero(unbounded))
        return x.astype(self.dtype)

    def contains(self, x):
        x = np.asarray(x)
        return x.shape == self.shape and bool(np.all(x >= self.low)) and bool(np.all(x <= self.high))

    def __contains__(self, x):
        return self.contains(x)

    def __repr__(self):
        return f"Box({self.low.min()}, {self.high.max()}, {self.shape}, {self.dtype})"


def box(low, high, shape, dtype):
    """Gymnasium's Box when Gymnasium is importable, else ours."""
    if _gymnasium is not None:
        return _gymnasium.spaces.Box(low=low, high=high, shape=shape, dtype=dtype)
    return Box(low, high, shape, dtype)
