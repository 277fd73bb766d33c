# Runs inside Blender (bench/peer_cycles.sh):
#   blender -b --factory-startup --python bench/peer_cycles.py -- SCENE.json SPP OUT.exr THREADS MAX_BOUNCES SEED
# Builds the Loom JSON scene SCENE.json in Blender (the subset the peer scenes use: mesh shapes
# from OBJ files, diffuse and F = 1 (rough)conductor materials, area emission, a constant
# environment, a look-at camera), renders it with Cycles on the CPU with the settings of issue
# 22 (box filter, no denoising, no clamping, no light threshold, no adaptive sampling, Standard
# view transform, 32-bit EXR) and prints one line "peer_cycles: render_s=... samples=...".
import json
import math
import os
import sys
import time

import bpy
from mathutils import Matrix, Vector

argv = sys.argv[sys.argv.index("--") + 1:]
scene_path, spp, out_path, threads, max_bounces, seed = (
    argv[0], int(argv[1]), argv[2], int(argv[3]), int(argv[4]), int(argv[5]))
desc = json.load(open(scene_path))
base = os.path.dirname(os.path.abspath(scene_path))


def rgb(v, default=0.0):
    if v is None:
        v = default
    if isinstance(v, (int, float)):
        return (float(v), float(v), float(v), 1.0)
    return (float(v[0]), float(v[1]), float(v[2]), 1.0)


def read_obj(path):
    verts, faces = [], []
    for line in open(path):
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            verts.append(tuple(float(x) for x in t[1:4]))
        elif t[0] == "f":
            faces.append(tuple(int(x.split("/")[0]) - 1 for x in t[1:]))
    return verts, faces


def bsdf_node(nodes, m):
    kind = m.get("type", "diffuse")
    if kind == "diffuse":
        n = nodes.new("ShaderNodeBsdfDiffuse")
        n.inputs["Color"].default_value = rgb(m.get("reflectance"), 0.5)
        n.inputs["Roughness"].default_value = 0.0  # Lambert
        return n
    if kind in ("conductor", "roughconductor"):
        if m.get("metal", "none") != "none" or "eta" in m:
            raise SystemExit("peer_cycles.py: only F = 1 conductors (metal none) map to Glossy")
        n = nodes.new("ShaderNodeBsdfGlossy")
        if kind == "conductor":
            n.distribution = "SHARP"
        else:
            if m.get("distribution", "ggx") != "ggx":
                raise SystemExit("peer_cycles.py: only GGX")
            n.distribution = "GGX"
            # Cycles squares its roughness: alpha = roughness^2.
            n.inputs["Roughness"].default_value = math.sqrt(float(m.get("alpha", 0.1)))
        n.inputs["Color"].default_value = rgb(m.get("specular_reflectance"), 1.0)
        return n
    raise SystemExit("peer_cycles.py: material type '%s' is not mapped" % kind)


def make_material(name, m, emission):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    nodes.clear()
    out = nodes.new("ShaderNodeOutputMaterial")
    surface = bsdf_node(nodes, m)
    if emission is None:
        links.new(surface.outputs[0], out.inputs["Surface"])
        return mat
    # Loom's area lights emit on the normal side only; Cycles' emission is two-sided, so the
    # back face gets the bare BSDF.
    emit = nodes.new("ShaderNodeEmission")
    emit.inputs["Color"].default_value = rgb(emission)
    emit.inputs["Strength"].default_value = 1.0
    add = nodes.new("ShaderNodeAddShader")
    links.new(emit.outputs[0], add.inputs[0])
    links.new(surface.outputs[0], add.inputs[1])
    back = bsdf_node(nodes, m)
    geo = nodes.new("ShaderNodeNewGeometry")
    mix = nodes.new("ShaderNodeMixShader")
    links.new(geo.outputs["Backfacing"], mix.inputs["Fac"])
    links.new(add.outputs[0], mix.inputs[1])
    links.new(back.outputs[0], mix.inputs[2])
    links.new(mix.outputs[0], out.inputs["Surface"])
    return mat


bpy.ops.wm.read_factory_settings(use_empty=True)
scene = bpy.context.scene
materials = desc.get("materials", {})
for i, s in enumerate(desc["shapes"]):
    if s.get("type") != "mesh" or not s.get("face_normals", False):
        raise SystemExit("peer_cycles.py: shape %d: only flat 'mesh' shapes are mapped" % i)
    verts, faces = read_obj(os.path.join(base, s["file"]))
    mesh = bpy.data.meshes.new(s.get("name", "shape%d" % i))
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    for p in mesh.polygons:
        p.use_smooth = False
    m = s.get("material", {})
    if isinstance(m, str):
        m = materials[m]
    mesh.materials.append(make_material(mesh.name + "_mat", m, s.get("emission")))
    obj = bpy.data.objects.new(mesh.name, mesh)
    scene.collection.objects.link(obj)

world = bpy.data.worlds.new("environment")
world.use_nodes = True
bg = world.node_tree.nodes["Background"]
env = desc.get("environment", {}).get("radiance")
bg.inputs["Color"].default_value = rgb(env, 0.0)
bg.inputs["Strength"].default_value = 1.0
scene.world = world

cam_desc = desc["camera"]
cam = bpy.data.cameras.new("camera")
cam.sensor_fit = "VERTICAL"  # Loom's fov is vertical
cam.angle = math.radians(float(cam_desc["fov"]))
cam.clip_start, cam.clip_end = 1e-3, 1e4
cam_obj = bpy.data.objects.new("camera", cam)
scene.collection.objects.link(cam_obj)
eye, target = Vector(cam_desc["origin"]), Vector(cam_desc["target"])
up = Vector(cam_desc.get("up", [0, 1, 0]))
f = (target - eye).normalized()
r = f.cross(up).normalized()
u = r.cross(f)
cam_obj.matrix_world = Matrix(((r.x, u.x, -f.x, eye.x), (r.y, u.y, -f.y, eye.y),
                               (r.z, u.z, -f.z, eye.z), (0, 0, 0, 1)))
scene.camera = cam_obj

film = cam_desc.get("film", [128, 128])
render = scene.render
render.engine = "CYCLES"
render.resolution_x, render.resolution_y = int(os.environ.get("WIDTH", film[0])), int(
    os.environ.get("HEIGHT", film[1]))
render.resolution_percentage = 100
render.threads_mode = "FIXED"
render.threads = threads
render.film_transparent = False
render.use_persistent_data = False
render.image_settings.file_format = "OPEN_EXR"
render.image_settings.color_depth = "32"
render.image_settings.exr_codec = "ZIP"
scene.view_settings.view_transform = "Standard"
scene.view_settings.look = "None"
scene.view_settings.exposure = 0.0
scene.view_settings.gamma = 1.0

c = scene.cycles
c.device = "CPU"
c.samples = spp
c.use_adaptive_sampling = False
c.use_denoising = False
c.seed = seed
c.use_animated_seed = False
c.pixel_filter_type = "BOX"
c.filter_width = 1.0
c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = max_bounces
c.volume_bounces = 0
c.transparent_max_bounces = 8
c.min_light_bounces = 0
c.min_transparent_bounces = 0
c.sample_clamp_direct = 0.0
c.sample_clamp_indirect = 0.0
c.blur_glossy = 0.0
c.caustics_reflective = True
c.caustics_refractive = True
c.light_sampling_threshold = 0.0

render.filepath = out_path
start = time.perf_counter()
bpy.ops.render.render(write_still=True)
elapsed = time.perf_counter() - start
print("peer_cycles: render_s=%.4f samples=%d width=%d height=%d threads=%d" %
      (elapsed, spp, render.resolution_x, render.resolution_y, threads))
