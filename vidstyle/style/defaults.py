"""Defaults of the behaviour-style stage, in one place: :func:`vidstyle.style.learn`,
:func:`vidstyle.style.style_params`, :func:`vidstyle.style.generate_sequence`, :class:`EventParams` and
the commands ``learn-style``, ``generate`` and ``evaluate style`` take theirs from here.
(:class:`~vidstyle.style.artifact.StyleParams` holds the same values; a test keeps them equal.)"""

from __future__ import annotations

# frame labels -> events
IGNORE: tuple[str, ...] = ("Guard", "Step")   # filler classes that are not actions
MIN_CONFIDENCE = 0.5                          # frames below are dropped
MIN_RUN = 3                                   # runs shorter (frames) are noise
MAX_GAP = 4                                   # a run resumed after at most this many noise frames is one event
SPLIT_REPEATS = True                          # cut back-to-back repeats of an action into events
# HMMs
SEED = 0
N_INIT = 4                                    # EM restarts per model
N_ITER = 200                                  # EM iterations per restart
ALPHA = 0.5                                   # Dirichlet pseudo-count per transition cell
LEARN_EMISSION = True                         # model (a) learns recognition confusions
EMISSION_PRIOR = 10.0                         # model (a): pseudo-events per row of the diagonal prior
MODES = "1-6"                                 # model (b): candidate numbers of behaviour modes
MODE_CRITERION = "heldout"                    # model (b): heldout | bic
# generation
GENERATE_LENGTH = 40                          # events per generated sequence
MODEL = "a"                                   # a | b | bigram
# data enough for the models (learn-style warns below): observed action transitions per transition
# probability of model (a), and events per free parameter of model (b)'s chosen modes
MIN_TRANSITIONS_PER_CELL = 1
MIN_EVENTS_PER_PARAMETER = 1
