"""The sphere drape in Blender's cloth, the baseline of `tailor`'s drape example, run alternately with it.

A 2 m square sheet of n x n vertices falls 0.5 m onto a sphere of radius 0.5 m (48 segments,
24 rings: the same sphere as `crates/cloth/src/shapes.rs`), 60 frames at 24 fps (stepped from
the rest state at frame 1 to frame 61, as `tailor`'s scene steps from frame 0 to 60), Blender's
Cotton preset (5 quality steps, or substeps, a frame; applied from the preset file Blender
ships, whose shear stiffness is 15 where a new cloth modifier's default is 5), self-collision
off or on. Prints the mean ms per frame (the cloth evaluation of each frame, stepped in
order) and the worst edge stretch l/L - 1 and compression 1 - l/L of any frame.

    blender -b --factory-startup --python bench/blender_drape.py -- 64 [--self]
"""

import ast
import re
import sys
import time
from pathlib import Path

import bpy

# Frames stepped, each after the one before; frame 1 is the rest state.
FRAMES = 60

argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
n = int(argv[0]) if argv else 64
self_collision = "--self" in argv

bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
scene.render.fps = 24
scene.frame_start = 1
scene.frame_end = FRAMES + 1

# The sheet: a grid of n x n vertices (since Blender 3.0 the subdivision count is faces per side).
bpy.ops.mesh.primitive_grid_add(x_subdivisions=n - 1, y_subdivisions=n - 1, size=2.0)
sheet = bpy.context.active_object
assert len(sheet.data.vertices) == n * n, len(sheet.data.vertices)
cloth = sheet.modifiers.new("Cloth", "CLOTH")
# The preset file sets `bpy.context.cloth.settings.<name> = <literal>` line by line, in the
# context of the properties editor; the same assignments go to this modifier's settings.
preset = next(
    (Path(folder) / "Cotton.py" for folder in bpy.utils.preset_paths("cloth")
     if (Path(folder) / "Cotton.py").exists()),
    None,
)
if preset is None:
    sys.exit("Blender's cloth preset Cotton.py was not found")
assignment = re.compile(r"^bpy\.context\.cloth\.settings\.(\w+) = (.+)$")
for line in preset.read_text().splitlines():
    if found := assignment.match(line):
        setattr(cloth.settings, found[1], ast.literal_eval(found[2]))
assert cloth.settings.quality == 5 and cloth.settings.shear_stiffness == 15
cloth.collision_settings.use_self_collision = self_collision
cloth.point_cache.frame_start = 1
cloth.point_cache.frame_end = FRAMES + 1

bpy.ops.mesh.primitive_uv_sphere_add(segments=48, ring_count=24, radius=0.5, location=(0, 0, -1))
bpy.context.active_object.modifiers.new("Collision", "COLLISION")

rest = [(e.vertices[0], e.vertices[1]) for e in sheet.data.edges]
start = [v.co.copy() for v in sheet.data.vertices]
rest_length = [(start[a] - start[b]).length for a, b in rest]

total = 0.0
worst = 0.0
squash = 0.0
scene.frame_set(1)
for frame in range(2, FRAMES + 2):
    t = time.perf_counter()
    scene.frame_set(frame)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    evaluated = sheet.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    total += time.perf_counter() - t
    p = [v.co.copy() for v in mesh.vertices]
    strains = [(p[a] - p[b]).length / l - 1.0 for (a, b), l in zip(rest, rest_length)]
    worst = max(worst, max(strains))
    squash = max(squash, -min(strains))
    evaluated.to_mesh_clear()

print(
    f"blender {bpy.app.version_string} {n}² self-collision {'on' if self_collision else 'off'}: "
    f"{1e3 * total / FRAMES:.1f} ms/frame, worst stretch {100 * worst:.1f}%, "
    f"worst compression {100 * squash:.1f}%"
)
