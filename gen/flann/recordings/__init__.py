"""Recordings in: the CSV format (read, write) and the checks made before fitting."""

from .checks import (MIN_FIT_POINTS, MonotonicSpan, check_duplicates, converter_of, converter_step,
                     estimate_noise_v, monotonic_span, prepare_for_fit)
from .csvio import (OPTIONAL, REQUIRED, MultipleSensors, Recordings, format_recordings, parse_recordings,
                    read_recordings, recording_sensors, write_recordings)

__all__ = ["MIN_FIT_POINTS", "MonotonicSpan", "MultipleSensors", "OPTIONAL", "REQUIRED", "Recordings", "recording_sensors", "check_duplicates",
           "converter_of", "converter_step", "estimate_noise_v", "format_recordings", "monotonic_span", "parse_recordings", "prepare_for_fit",
           "read_recordings", "write_recordings"]
