#!/usr/bin/python3
# SPDX-License-Identifier: MIT
"""The plugin's panel speaks the library's vocabulary (ctest paraview.vocabulary): every property
of uvr_volume.xml that names a setting (uvr_setting="...") has that setting's default, a range
inside the setting's, and for a choice exactly its choices in its order (the representation
passes the index into them). Run with the build's Python module on PYTHONPATH."""
import sys
import xml.etree.ElementTree as ET

import uvr

xml_path = sys.argv[1]
vocabulary = {s["name"]: s for s in uvr.SETTINGS}
failures = []
checked = 0
for prop in ET.parse(xml_path).getroot().iter():
    name = prop.get("uvr_setting")
    if name is None:
        continue
    checked += 1
    what = "%s (%s)" % (prop.get("name"), name)
    s = vocabulary.get(name)
    if s is None:
        failures.append("%s: no such setting in the vocabulary" % what)
        continue
    default = prop.get("default_values")
    enum = prop.find("EnumerationDomain")
    if enum is not None:
        texts = [e.get("text") for e in enum.findall("Entry")]
        values = [int(e.get("value")) for e in enum.findall("Entry")]
        if texts != s["choices"] or values != list(range(len(texts))):
            failures.append("%s: entries %s, the vocabulary's choices %s" % (what, texts,
                                                                             s["choices"]))
        if s["choices"][int(default)] != s["default"]:
            failures.append("%s: default %s, the vocabulary's %s" % (what, default, s["default"]))
        continue
    if s["type"] == "flag":
        if bool(int(default)) != s["default"]:
            failures.append("%s: default %s, the vocabulary's %s" % (what, default, s["default"]))
        continue
    # Numbers: the default (0 stands for a per-mesh default, null in the vocabulary) and range.
    expected = 0.0 if s["default"] is None else float(s["default"])
    if abs(float(default) - expected) > 1e-6 * max(1.0, abs(expected)):
        failures.append("%s: default %s, the vocabulary's %s" % (what, default, s["default"]))
    rng = prop.find("DoubleRangeDomain")
    if rng is None:
        rng = prop.find("IntRangeDomain")
    if rng is not None:
        lo, hi = rng.get("min"), rng.get("max")
        if lo is not None and float(lo) < s["min"] - 1e-6:
            failures.append("%s: min %s below the vocabulary's %s" % (what, lo, s["min"]))
        if hi is not None and "max" in s and float(hi) > s["max"] + 1e-4:
            failures.append("%s: max %s above the vocabulary's %s" % (what, hi, s["max"]))
for f in failures:
    print("FAIL  " + f)
print("%d properties checked against the vocabulary, %d mismatches" % (checked, len(failures)))
sys.exit(1 if failures or checked == 0 else 0)
