# Imports a scene.glb with Blender's own glTF importer and prints, as JSON on the last line, the
# frame objects, their vertex and UV-layer counts, the object visible at each Blender frame
# 0..N (the importer maps glTF time t to frame t * fps, starting at 0), and frame 0's world
# bounding box (Blender is Z up like confluent).
#   blender -b --factory-startup --python gltf_blender_check.py -- scene.glb FPS
import json
import sys

import bpy
import numpy

# Blender 3.4's importer (Debian 12) still uses numpy.bool, which numpy 1.24 removed.
if not hasattr(numpy, "bool"):
    numpy.bool = bool

path, fps = sys.argv[sys.argv.index("--") + 1], int(sys.argv[sys.argv.index("--") + 2])
for obj in list(bpy.data.objects):
    bpy.data.objects.remove(obj)
scene = bpy.context.scene
scene.render.fps = fps
report = {}
try:
    report["import"] = list(bpy.ops.import_scene.gltf(filepath=path))
except Exception as error:  # the importer's message, e.g. an unsupported required extension
    report["import_error"] = str(error).splitlines()[-1] if str(error) else repr(error)
frames = sorted((o for o in bpy.data.objects if o.name.startswith("frame_")), key=lambda o: o.name)
report["frames"] = [o.name for o in frames]
report["vertices"] = [len(o.data.vertices) for o in frames]
report["uv_layers"] = [len(o.data.uv_layers) for o in frames]
report["visible"] = []
for f in range(len(frames)):
    scene.frame_set(f)
    report["visible"].append([o.name for o in frames if o.matrix_world.to_scale().length > 1e-9])
if frames:
    scene.frame_set(0)
    points = [frames[0].matrix_world @ v.co for v in frames[0].data.vertices]
    report["frame0_min"] = [min(p[a] for p in points) for a in range(3)]
    report["frame0_max"] = [max(p[a] for p in points) for a in range(3)]
print(json.dumps(report))
