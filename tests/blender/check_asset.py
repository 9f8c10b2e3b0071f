# Imports a glTF headless and prints what Blender made of it as one JSON line (prefix
# "TWOPASS_RESULT "): every object's type, a mesh's UV maps, materials and vertex count, each
# material's `lightMap` custom property (the glTF material extras), and the images.
# Usage: blender -b --factory-startup -P check_asset.py -- FILE.glb
import json
import sys

import bpy
import numpy

# Debian 12's Blender 3.4 glTF add-on uses numpy.bool, which numpy 1.24 removed.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

path = sys.argv[sys.argv.index("--") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=path)
objects = {}
for o in bpy.context.scene.objects:
    entry = {"type": o.type}
    if o.type == "MESH":
        entry["uv_maps"] = [uv.name for uv in o.data.uv_layers]
        entry["materials"] = [s.material.name for s in o.material_slots if s.material]
        entry["vertices"] = len(o.data.vertices)
    objects[o.name] = entry
materials = {}
for m in bpy.data.materials:
    lm = m.get("lightMap")
    materials[m.name] = {"lightMap": {k: lm[k] for k in lm.keys()} if lm is not None else None}
images = [i.name for i in bpy.data.images]
print("TWOPASS_RESULT " + json.dumps({"objects": objects, "materials": materials, "images": images}))
