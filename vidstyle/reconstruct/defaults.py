"""The reconstruction's defaults, chosen by ``scripts/validate_reconstruct.py`` on the demo's validation
performers (``pipelines/kickboxing/validation/reconstruct.json``: every value tried and its score; the test
performers never took part). ``tests/test_reconstruct_defaults.py`` checks that these are that file's
choices and that the CLI and the library default to them."""

METHOD = "olng"        # validation: olng beat nn and subsequence
K = 64                 # neighbours per frame: 64 beat 16, 32 and 128
N_BLEND = 8            # neighbours blended: 8 (16 within the 0.1 mm tie; 1, 4 and 32 worse)
WINDOW_S = 0.25        # OLNG window, seconds: all of 0.25-2 s within the tie, the shortest kept
SMOOTH_FRAMES = 1.0    # Gaussian sigma of the pose over time, frames: 1 beat 0, 2 and 3
