"""A procedural performer: body proportions, movement style and behaviour (a Markov chain over the six
actions with per-action durations), all drawn from one seed."""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from .actions import ACTIONS, BASE_SECONDS
from .skeleton import Body
from .transitions import draw_transition_styles


@dataclass(frozen=True)
class MovementTraits:
    """How a performer moves. Durations are divided by ``speed``; differences from the reference
    guard are multiplied by ``amplitude``; ``variation`` is the spread of per-repetition noise."""

    speed: float = 1.0
    amplitude: float = 1.0
    guard_height: float = 0.0  # arm lengths added to both fists' guard height
    stance_width: float = 1.0  # scales the foot placement of the stance
    lead: str = "orthodox"  # "orthodox" (left forward) or "southpaw" (mirror image)
    variation: float = 0.03
    crouch: float = 0.0  # statures the stance is lower
    bounce: float = 0.006  # statures of the guard's up-down bounce
    bounce_hz: float = 1.8
    tempo: tuple[float, ...] = (1.0,) * len(ACTIONS)  # per-action duration factors (this performer's rhythm)
    gap_seconds: float = 0.5  # mean guard pause between actions in a performance
    step_prob: float = 0.15  # chance that a pause contains a step
    # how much a punch moves the feet and hips (0..1; actions.PUNCH_FOOTWORK): 0, the default, keeps the lower body
    # in the guard while the arms strike; never drawn by random(), so a performer is the same with or without it
    footwork: float = 0.0

    def to_dict(self) -> dict:
        d = asdict(self)
        if not self.footwork:
            del d["footwork"]  # the documents of datasets made without footwork stay as they were
        return {k: (round(v, 6) if isinstance(v, float) else [round(x, 6) for x in v] if isinstance(v, tuple) else v)
                for k, v in d.items()}

    @classmethod
    def from_dict(cls, d: dict) -> MovementTraits:
        return cls(**{**d, "tempo": tuple(d.get("tempo", (1.0,) * len(ACTIONS)))})

    @classmethod
    def random(cls, rng: np.random.Generator) -> MovementTraits:
        return cls(
            speed=float(rng.uniform(0.8, 1.25)),
            amplitude=float(rng.uniform(0.85, 1.1)),
            guard_height=float(rng.uniform(-0.08, 0.06)),
            stance_width=float(rng.uniform(0.85, 1.2)),
            lead="southpaw" if rng.random() < 0.3 else "orthodox",
            variation=float(rng.uniform(0.015, 0.05)),
            crouch=float(rng.uniform(0.0, 0.025)),
            bounce=float(rng.uniform(0.002, 0.01)),
            bounce_hz=float(rng.uniform(1.4, 2.4)),
            tempo=tuple(float(x) for x in rng.uniform(0.85, 1.2, len(ACTIONS))),
            gap_seconds=float(rng.uniform(0.3, 0.8)),
            step_prob=float(rng.uniform(0.05, 0.25)),
        )


@dataclass(frozen=True)
class Chain:
    """A first-order Markov chain over :data:`ACTIONS` with per-action durations.

    ``duration_frames[a] = (mean, sd)`` is in frames of the dataset's video rate (``video_fps``)."""

    start: np.ndarray  # (A,)
    transition: np.ndarray  # (A, A), rows sum to 1; self-transitions allowed
    duration_frames: dict[str, tuple[float, float]]
    video_fps: float = 20.0

    @classmethod
    def random(cls, rng: np.random.Generator, style: MovementTraits, video_fps: float = 20.0) -> Chain:
        """Rows mix a sparse Dirichlet draw with two favourite follow-ups, so performers differ clearly."""
        A = len(ACTIONS)
        start = rng.dirichlet(np.full(A, 0.8))
        trans = np.empty((A, A))
        for a in range(A):
            row = 0.4 * rng.dirichlet(np.full(A, 0.5))
            fav = rng.choice(A, size=2, replace=False)
            row[fav] += (0.38, 0.22)
            trans[a] = row / row.sum()
        durations = {}
        for k, a in enumerate(ACTIONS):
            mean = BASE_SECONDS[a] * style.tempo[k] / style.speed * video_fps
            durations[a] = (float(mean), float(max(0.08 * mean, 0.6)))
        return cls(start, trans, durations, video_fps)

    def to_dict(self) -> dict:
        return {
            "actions": list(ACTIONS),
            "start": [round(float(x), 8) for x in self.start],
            "transition": [[round(float(x), 8) for x in row] for row in self.transition],
            "duration_frames": {a: [round(m, 6), round(s, 6)] for a, (m, s) in self.duration_frames.items()},
        }

    def sample_actions(self, n: int, rng: np.random.Generator) -> list[str]:
        out = [int(rng.choice(len(ACTIONS), p=self.start))]
        for _ in range(n - 1):
            out.append(int(rng.choice(len(ACTIONS), p=self.transition[out[-1]])))
        return [ACTIONS[i] for i in out]

    def sample_duration(self, action: str, rng: np.random.Generator, min_frames: int = 4) -> int:
        """Duration of one repetition in video frames."""
        mean, sd = self.duration_frames[action]
        return int(max(min_frames, round(rng.normal(mean, sd))))


@dataclass(frozen=True)
class Performer:
    id: str
    body: Body
    style: MovementTraits
    chain: Chain
    transitions: tuple[tuple[str, str, str], ...] = ()  # (from, to, kind): see :mod:`.transitions`

    @classmethod
    def random(cls, performer_id: str, rng: np.random.Generator, video_fps: float = 20.0) -> Performer:
        body = Body.random(rng)
        style = MovementTraits.random(rng)
        chain = Chain.random(rng, style, video_fps)
        # drawn last, so body, style and chain are those of a performer without transition styles
        return cls(performer_id, body, style, chain, draw_transition_styles(rng, chain.transition))

    def transition_kind(self, src: str, dst: str) -> str | None:
        """This performer's way of moving from action ``src`` to ``dst`` (None: a plain guard pause)."""
        for a, b, kind in self.transitions:
            if a == src and b == dst:
                return kind
        return None

    def to_dict(self) -> dict:
        return {"id": self.id, "body": self.body.to_dict(), "style": self.style.to_dict(), "chain": self.chain.to_dict(),
                "transitions": [{"from": a, "to": b, "kind": k} for a, b, k in self.transitions]}
