"""How a performer looks: clothing colours and build. Colours are BGR tuples of 0-255 ints."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .body import GLOVES, HAIR, LEG, N_MATERIALS, SHIRT, SHOES, SKIN, SLEEVE, TROUSERS

Colour = tuple[int, int, int]

SKIN_TONES: list[Colour] = [(189, 209, 241), (150, 180, 224), (120, 160, 210), (95, 130, 180), (70, 95, 140), (50, 70, 105)]
HAIR_COLOURS: list[Colour] = [(20, 20, 25), (25, 45, 70), (40, 70, 110), (90, 150, 200), (150, 150, 150), (30, 30, 90)]
SHIRT_COLOURS: list[Colour] = [
    (200, 60, 40), (40, 40, 200), (40, 160, 40), (30, 200, 230), (230, 230, 230), (40, 40, 40),
    (160, 60, 160), (0, 130, 255), (160, 160, 40), (120, 80, 40), (90, 90, 200), (200, 200, 90),
]
TROUSER_COLOURS: list[Colour] = [
    (90, 50, 30), (40, 40, 40), (130, 130, 130), (30, 60, 120), (160, 110, 60), (20, 20, 120),
    (60, 100, 60), (200, 200, 200), (110, 40, 90),
]
SHOE_COLOURS: list[Colour] = [(30, 30, 30), (240, 240, 240), (40, 60, 100), (60, 60, 160), (150, 90, 40)]
GLOVE_COLOURS: list[Colour] = [(30, 30, 200), (200, 80, 30), (20, 20, 20), (240, 240, 240), (40, 160, 40)]


@dataclass(frozen=True)
class Appearance:
    """Clothing colours (BGR) and build of a rendered performer.

    ``shoes=None`` means bare feet, ``gloves=None`` bare hands; ``sleeves`` is ``"short"`` or
    ``"long"``; ``shorts`` leaves the lower legs bare; ``build`` scales every limb's thickness.
    """

    skin: Colour = (150, 180, 224)
    hair: Colour = (25, 45, 70)
    shirt: Colour = (200, 60, 40)
    trousers: Colour = (90, 50, 30)
    shoes: Colour | None = (30, 30, 30)
    gloves: Colour | None = None
    sleeves: str = "short"
    shorts: bool = False
    build: float = 1.0

    def __post_init__(self) -> None:
        if self.sleeves not in ("short", "long"):
            raise ValueError(f"sleeves must be 'short' or 'long', got {self.sleeves!r}")
        if not 0.3 <= float(self.build) <= 3.0:
            raise ValueError(f"build must be between 0.3 and 3, got {self.build}")

    @classmethod
    def random(cls, seed: int | np.random.Generator | None = None) -> Appearance:
        """A random but plausible performer (deterministic for a given seed)."""
        rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)

        def pick(options):
            return tuple(int(v) for v in options[int(rng.integers(len(options)))])

        def jitter(c):
            return tuple(int(np.clip(v + rng.integers(-15, 16), 0, 255)) for v in c)

        shirt = jitter(pick(SHIRT_COLOURS))
        trousers = jitter(pick(TROUSER_COLOURS))
        # keep shirt and trousers distinguishable
        for _ in range(10):
            if np.abs(np.subtract(shirt, trousers)).sum() > 120:
                break
            trousers = jitter(pick(TROUSER_COLOURS))
        return cls(
            skin=jitter(pick(SKIN_TONES)),
            hair=pick(HAIR_COLOURS),
            shirt=shirt,
            trousers=trousers,
            shoes=None if rng.random() < 0.25 else pick(SHOE_COLOURS),
            gloves=pick(GLOVE_COLOURS) if rng.random() < 0.35 else None,
            sleeves="long" if rng.random() < 0.35 else "short",
            shorts=bool(rng.random() < 0.3),
            build=float(np.round(rng.uniform(0.85, 1.2), 3)),
        )

    def palette(self) -> np.ndarray:
        """(N_MATERIALS, 3) float32 BGR colours indexed by the material ids of :mod:`.body`."""
        pal = np.zeros((N_MATERIALS, 3), dtype=np.float32)
        pal[SKIN] = self.skin
        pal[HAIR] = self.hair
        pal[SHIRT] = self.shirt
        pal[SLEEVE] = self.shirt
        pal[TROUSERS] = self.trousers
        pal[LEG] = self.trousers
        pal[SHOES] = self.shoes if self.shoes is not None else self.skin
        pal[GLOVES] = self.gloves if self.gloves is not None else self.skin
        return pal

    def to_dict(self) -> dict:
        return asdict(self)

    @classmethod
    def from_dict(cls, d: dict) -> Appearance:
        d = dict(d)
        for k in ("skin", "hair", "shirt", "trousers", "shoes", "gloves"):
            if d.get(k) is not None:
                d[k] = tuple(int(v) for v in d[k])
        return cls(**d)
