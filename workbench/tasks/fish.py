r"""A simulated fish on a table: flesh surface, backbone, touch events.

The fish lies along the world y axis, centred on ``x = center_x``, on a table
at height ``table_z`` (world frame of Kang's Fig. 7: z up). Its flesh is a
hump over the table, its backbone a ridge inside it. Both heights vary along
the fish by a smooth random amount drawn from ``seed``, so the cutting
program does not know them in advance and must react to touch events, as in
Kang (2007, §5): "bone positions are not known in advance".

.. math::
    z_\text{flesh}(x, y) = z_\text{table} + h_f \sqrt{\sin(\pi u)}
        \sqrt{1 - (\Delta x / w)^2} + \delta_f(u), \qquad
    z_\text{bone}(y) = z_\text{table} + h_b + \delta_b(u),

with :math:`u = (y - y_\text{head}) / (y_\text{tail} - y_\text{head})` and
δ sums of three random sinusoids bounded by the given variations.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from workbench.errors import InputError

FloatArray = npt.NDArray[np.float64]

#: Contact names reported by :meth:`SimulatedFish.get_contact`.
FLESH = "flesh"
BONE = "bone"

_HARMONICS = 3


def check_scale_factor(value: float, what: str) -> float:
    """``value`` as a float if it is a positive finite number (a scale factor).

    Raises:
        InputError: Otherwise, naming ``what``.
    """
    if not isinstance(value, float | int) or not math.isfinite(value) or value <= 0:
        raise InputError(f"{what} must be a positive finite number, got {value!r}")
    return float(value)


class SimulatedFish:
    """A fish with a flesh surface and a backbone of seeded random heights.

    Args:
        seed: Seed of the random height variations.
        head_y: y of the head end [m].
        tail_y: y of the tail end [m], > ``head_y``.
        center_x: x of the backbone [m].
        half_width: Half width of the body [m].
        table_z: Height of the table [m].
        thickness: Nominal flesh height above the table at mid-body [m].
        bone_height: Nominal height of the backbone top above the table [m].
        bone_half_width: Half width of the backbone [m].
        flesh_variation: Bound of the random flesh height change [m].
        bone_variation: Bound of the random backbone height change [m].

    Raises:
        InputError: If a size is not positive and finite, the ends are in the
            wrong order, or the backbone is not inside the flesh.
    """

    def __init__(
        self,
        seed: int = 0,
        *,
        head_y: float = 0.17,
        tail_y: float = 0.61,
        center_x: float = 0.0,
        half_width: float = 0.05,
        table_z: float = 0.12,
        thickness: float = 0.06,
        bone_height: float = 0.025,
        bone_half_width: float = 0.008,
        flesh_variation: float = 0.004,
        bone_variation: float = 0.004,
    ) -> None:
        values = dict(
            head_y=head_y,
            tail_y=tail_y,
            center_x=center_x,
            table_z=table_z,
            half_width=half_width,
            thickness=thickness,
            bone_height=bone_height,
            bone_half_width=bone_half_width,
            flesh_variation=flesh_variation,
            bone_variation=bone_variation,
        )
        for name, value in values.items():
            if not isinstance(value, float | int) or not math.isfinite(value):
                raise InputError(f"fish {name} must be a finite number, got {value!r}")
        for name in ("half_width", "thickness", "bone_height", "bone_half_width"):
            if values[name] <= 0.0:
                raise InputError(f"fish {name} must be > 0, got {values[name]:g}")
        for name in ("flesh_variation", "bone_variation"):
            if values[name] < 0.0:
                raise InputError(f"fish {name} must be >= 0, got {values[name]:g}")
        if tail_y <= head_y:
            raise InputError(
                f"fish tail_y ({tail_y:g}) must exceed head_y ({head_y:g})"
            )
        if bone_height + bone_variation >= thickness - flesh_variation:
            raise InputError("the backbone must lie inside the flesh")
        self.seed = int(seed)
        self.head_y, self.tail_y = float(head_y), float(tail_y)
        self.center_x, self.table_z = float(center_x), float(table_z)
        self.half_width, self.thickness = float(half_width), float(thickness)
        self.bone_height = float(bone_height)
        self.bone_half_width = float(bone_half_width)
        self.flesh_variation = float(flesh_variation)
        self.bone_variation = float(bone_variation)
        rng = np.random.default_rng(self.seed)
        self._flesh = self._harmonics(rng, flesh_variation)
        self._bone = self._harmonics(rng, bone_variation)

    def scaled(self, factor: float) -> SimulatedFish:
        """The same fish (same seed) with every length multiplied by ``factor``.

        Positions, sizes and the bounds of the random height variations all
        scale, so ``scaled(s).flesh_top(s x, s y) = s flesh_top(x, y)`` (to
        rounding): the fish of Kang's cell scaled to another arm
        (:func:`~workbench.tasks.fish_program.get_cell_scale`).

        Raises:
            InputError: If ``factor`` is not a positive finite number.
        """
        f = check_scale_factor(factor, "fish scale")
        return SimulatedFish(
            self.seed,
            head_y=f * self.head_y,
            tail_y=f * self.tail_y,
            center_x=f * self.center_x,
            half_width=f * self.half_width,
            table_z=f * self.table_z,
            thickness=f * self.thickness,
            bone_height=f * self.bone_height,
            bone_half_width=f * self.bone_half_width,
            flesh_variation=f * self.flesh_variation,
            bone_variation=f * self.bone_variation,
        )

    @staticmethod
    def _harmonics(rng: np.random.Generator, bound: float) -> list[tuple[float, ...]]:
        weights = rng.uniform(0.2, 1.0, _HARMONICS)
        weights *= bound / weights.sum()  # |sum| <= bound
        frequencies = rng.uniform(1.0, 4.0, _HARMONICS)
        phases = rng.uniform(0.0, 2.0 * math.pi, _HARMONICS)
        return list(zip(weights, frequencies, phases, strict=True))

    def __repr__(self) -> str:
        return (
            f"SimulatedFish(seed={self.seed}, y=[{self.head_y:g}, {self.tail_y:g}], "
            f"table_z={self.table_z:g})"
        )

    def _u(self, y: float) -> float:
        return (y - self.head_y) / (self.tail_y - self.head_y)

    @staticmethod
    def _wave(terms: list[tuple[float, ...]], u: float) -> float:
        return sum(a * math.sin(2.0 * math.pi * f * u + p) for a, f, p in terms)

    def flesh_top(self, x: float, y: float) -> float:
        """Height [m] of the flesh surface above (x, y); -inf off the fish."""
        u = self._u(y)
        dx = (x - self.center_x) / self.half_width
        if not (0.0 < u < 1.0 and abs(dx) < 1.0):
            return -math.inf
        shape = math.sqrt(math.sin(math.pi * u) * (1.0 - dx * dx))
        return self.table_z + self.thickness * shape + self._wave(self._flesh, u)

    def bone_top(self, x: float, y: float) -> float:
        """Height [m] of the backbone top above (x, y); -inf off the bone."""
        u = self._u(y)
        if not (0.05 < u < 0.95 and abs(x - self.center_x) < self.bone_half_width):
            return -math.inf
        return self.table_z + self.bone_height + self._wave(self._bone, u)

    def get_contact(self, position: npt.ArrayLike) -> str | None:
        """What a tool tip at ``position`` (3,) [m] is in.

        Returns:
            ``"bone"`` at or below the backbone top, ``"flesh"`` at or below
            the flesh surface, else None.
        """
        x, y, z = (float(c) for c in np.asarray(position, dtype=np.float64))
        if z <= self.bone_top(x, y):
            return BONE
        if z <= self.flesh_top(x, y):
            return FLESH
        return None

    def sample_profiles(self, y: npt.ArrayLike) -> tuple[FloatArray, FloatArray]:
        """Flesh and bone heights along the backbone (x = ``center_x``), for plots.

        Args:
            y: Positions (K,) [m].

        Returns:
            ``(flesh_z, bone_z)``, each (K,) [m], NaN off the fish / bone.
        """
        ys = np.asarray(y, dtype=np.float64).ravel()
        flesh = np.array([self.flesh_top(self.center_x, v) for v in ys])
        bone = np.array([self.bone_top(self.center_x, v) for v in ys])
        flesh[~np.isfinite(flesh)] = np.nan
        bone[~np.isfinite(bone)] = np.nan
        return flesh, bone


__all__ = ["BONE", "FLESH", "SimulatedFish"]
