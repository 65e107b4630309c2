"""SSTA: stereo traversability for ground robots, from Python.

A thin binding over the C++ library (docs/python.md): open maps and query them with NumPy
arrays, classify stereo pairs, build maps from sequences, read and edit configs. Every query
loops in C++ with the GIL released.

Frames and units: world frame W right-handed with z up, metres; yaw in radians from +x towards
+y; slopes in degrees where the name says `_deg`. Classes: 0 unknown, 1 traversable,
2 semi-traversable, 3 non-traversable, 4 undecided (docs/conventions.md).

Errors: a bad argument raises ValueError naming it; a missing input file FileNotFoundError
naming the file; bad input the library rejects (a corrupt map, a config value out of range)
raises ssta.Error, a subclass of ValueError, with the message `ssta` on the command line prints.
"""

from ._ssta import MAP_ONLY, Error, Map, __version__

# A map-only build (cmake -DSSTA_MAP_ONLY=ON) binds maps alone: Map and Error.
if not MAP_ONLY:
    from ._ssta import (
        CameraCalibration,
        Config,
        ConfigSection,
        FramePipeline,
        LABEL_RULES,
        StereoCalibration,
        build_map,
        classify,
    )

#: Class ids (docs/interfaces.md, section 3).
UNKNOWN, TRAVERSABLE, SEMI_TRAVERSABLE, NON_TRAVERSABLE, UNDECIDED = 0, 1, 2, 3, 4

#: Class colours (R, G, B) as the exports draw them; undecided has none (grey here).
CLASS_COLOURS = {
    UNKNOWN: (0, 0, 0),
    TRAVERSABLE: (0, 255, 0),
    SEMI_TRAVERSABLE: (0, 0, 255),
    NON_TRAVERSABLE: (255, 0, 0),
    UNDECIDED: (128, 128, 128),
}

__all__ = [
    "Error",
    "MAP_ONLY",
    "Map",
    "UNKNOWN",
    "TRAVERSABLE",
    "SEMI_TRAVERSABLE",
    "NON_TRAVERSABLE",
    "UNDECIDED",
    "CLASS_COLOURS",
]
if not MAP_ONLY:
    __all__ += [
        "CameraCalibration",
        "Config",
        "ConfigSection",
        "FramePipeline",
        "LABEL_RULES",
        "StereoCalibration",
        "build_map",
        "classify",
    ]
