"""Video in and out: the one reader (frames by decoded index, streamed, at a working rate and size) and the
one writer (atomic, constant or variable frame rate). Nothing else in vidstyle decodes or encodes video."""

from .reader import VideoInfo, VideoReader, probe, working_indices
from .writer import CODECS, VideoWriter, write_video

__all__ = ["CODECS", "VideoInfo", "VideoReader", "VideoWriter", "probe", "working_indices", "write_video"]
