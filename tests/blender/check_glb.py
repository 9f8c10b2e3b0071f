# Imports a twopass .glb headless and prints what Blender made of it as one JSON line
# (prefix "TWOPASS_RESULT "): every mesh object's dimensions in metres, its UV maps, and the
# images, and every camera's vertical field of view (radians), aspect ratio, location and the
# world directions of its view (-Z) and up (+Y) axes, in Blender's frame (z up). Usage: blender -b --factory-startup -P check_glb.py -- FILE.glb
import json
import sys

import bpy
import mathutils
import numpy

# Debian 12's Blender 3.4 glTF importer uses numpy.bool, which numpy 1.24 (Debian 12's)
# removed; the alias it meant is the builtin bool.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

path = sys.argv[sys.argv.index("--") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.import_scene.gltf(filepath=path)
objects = {}
for o in bpy.context.scene.objects:
    if o.type != "MESH":
        continue
    objects[o.name] = {
        "dimensions": list(o.dimensions),
        "uv_maps": [uv.name for uv in o.data.uv_layers],
        "materials": [s.material.name for s in o.material_slots if s.material],
    }
def emission_source(material):
    # The image feeding the Principled BSDF's Emission, and the UV map its vector comes from.
    if not material.use_nodes:
        return None
    for node in material.node_tree.nodes:
        if node.type != "BSDF_PRINCIPLED":
            continue
        links = node.inputs["Emission"].links
        while links and links[0].from_node.type != "TEX_IMAGE":
            upstream = [i for i in links[0].from_node.inputs if i.links]
            links = upstream[0].links if upstream else None
        if not links:
            return None
        tex = links[0].from_node
        uv = None
        vec = tex.inputs["Vector"].links
        while vec:
            n = vec[0].from_node
            if n.type == "UVMAP":
                uv = n.uv_map
                break
            upstream = [i for i in n.inputs if i.links]
            vec = upstream[0].links if upstream else None
        return {"image": tex.image.name if tex.image else None, "uv_map": uv}
    return None


materials = {m.name: emission_source(m) for m in bpy.data.materials}
cameras = {}
for o in bpy.context.scene.objects:
    if o.type != "CAMERA":
        continue
    rotation = o.matrix_world.to_3x3().normalized()
    render = bpy.context.scene.render
    cameras[o.name] = {
        "angle_y": o.data.angle_y,
        "sensor_fit": o.data.sensor_fit,
        "aspect": render.resolution_x / render.resolution_y,
        "location": list(o.matrix_world.translation),
        "forward": list(rotation @ mathutils.Vector((0.0, 0.0, -1.0))),
        "up": list(rotation @ mathutils.Vector((0.0, 1.0, 0.0))),
    }
images = [{"name": i.name, "size": list(i.size)} for i in bpy.data.images]
print(
    "TWOPASS_RESULT "
    + json.dumps(
        {"objects": objects, "images": images, "materials": materials, "cameras": cameras}
    )
)
