# Builds a small room in Blender headless and exports it as glTF binary, as an artist would:
# a floor with an image texture, a crate, an emissive lamp plane, a point light of 250 W and a camera.
# Usage: blender -b --factory-startup -P export_room.py -- OUT.glb
import sys

import bpy
import numpy

# Debian 12's Blender 3.4 glTF add-on uses numpy.bool, which numpy 1.24 removed.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

out = sys.argv[sys.argv.index("--") + 1]
bpy.ops.wm.read_factory_settings(use_empty=True)
def material(name, colour, emission=None, strength=0.0, texture=False):
    m = bpy.data.materials.new(name)
    m.use_nodes = True
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.8
    if emission:
        bsdf.inputs["Emission"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = strength
    if texture:
        img = bpy.data.images.new("checker", 8, 8)
        img.generated_type = "COLOR_GRID"
        img.pack()
        tex = m.node_tree.nodes.new("ShaderNodeTexImage")
        tex.image = img
        m.node_tree.links.new(tex.outputs["Color"], bsdf.inputs["Base Color"])
    return m
bpy.ops.mesh.primitive_plane_add(size=4.0, location=(0, 0, 0))
floor = bpy.context.object
floor.name = "Floor"
floor.data.materials.append(material("Checker", (0.8, 0.8, 0.8), texture=True))
bpy.ops.mesh.primitive_cube_add(size=1.0, location=(0.5, 0.3, 0.5))
crate = bpy.context.object
crate.name = "Crate"
crate.data.materials.append(material("Wood", (0.6, 0.4, 0.2)))
bpy.ops.mesh.primitive_plane_add(size=1.0, location=(0, 0, 2.5), rotation=(3.14159265, 0, 0))
lamp = bpy.context.object
lamp.name = "Lamp"
lamp.data.materials.append(material("LampGlow", (0, 0, 0), emission=(1, 1, 1), strength=10.0))
bpy.ops.object.light_add(type="POINT", location=(1, 1, 2))
bpy.context.object.name = "Bulb"
bpy.context.object.data.energy = 250.0
bpy.ops.object.camera_add(location=(0, -6, 2), rotation=(1.3, 0, 0))
bpy.context.object.name = "Cam"
bpy.ops.export_scene.gltf(filepath=out, export_format="GLB", export_cameras=True, export_lights=True)
