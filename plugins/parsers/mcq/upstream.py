"""The upstream commits the multiple-choice rules follow (one place, so a parser's description,
the docs and the probe corpus name the same versions)."""

from __future__ import annotations

LMMS_EVAL = "EvolvingLMMs-Lab/lmms-eval@75571cfe0fa36ca5ec2e6aa2bb268f9d38295af3"
VLMEVALKIT = "open-compass/VLMEvalKit@e8e78f05f3080fe28154f2130321f17951c3be94"
VIEWSPATIAL_BENCH = "ZJU-REAL/ViewSpatial-Bench@2e85a5e41a29e7919b1d326d8aba316661579983"
MINDCUBE = "mll-lab-nu/MindCube@6d8fd9acdf5b80769373a21cdbfcf068ab356e0f"
MMSI_BENCH = "InternRobotics/MMSI-Bench@5de2f3d2eb0159dbcc76790074029aa400143603"
OMNISPATIAL = "qizekun/OmniSpatial@208bac258d8671c6857b3be2834997936ba7fc51"
