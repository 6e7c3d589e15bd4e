#!/usr/bin/env python3
"""Writes layered.usdc and layered.usdz from layered.usda with Pixar's USD (usd-core).

    python3 -m venv /tmp/usd-core && /tmp/usd-core/bin/pip install usd-core
    cd tests/data/usd && /tmp/usd-core/bin/python make_binaries.py
"""

from pxr import Sdf, UsdUtils

layer = Sdf.Layer.FindOrOpen("layered.usda")
layer.Export("layered.usdc")
UsdUtils.CreateNewUsdzPackage(Sdf.AssetPath("layered.usdc"), "layered.usdz")
