"""The papers' notation for a body about a fixed point, shared by every fixed-point regime (Ismail 2021, Shaker et
al.): a = A/C, b = B/C, the unit centre-of-mass direction (x0', y0', z0'), and the combinations A1, B1, C1 their
equations are written in."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class BodyRatios:
    """A body in both papers' notation: a = A/C, b = B/C, the unit centre-of-mass direction (x0', y0', z0'), and
    A1 = (1−b)/a, B1 = (a−1)/b, C1 = b−a."""

    a: float
    b: float
    x0: float
    y0: float
    z0: float

    @property
    def A1(self) -> float:
        return (1 - self.b) / self.a

    @property
    def B1(self) -> float:
        return (self.a - 1) / self.b

    @property
    def C1(self) -> float:
        return self.b - self.a
