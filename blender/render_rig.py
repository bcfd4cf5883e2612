"""Run inside Blender (blender -b --python blender/render_rig.py -- ARGS): rebuilds a woven
scene in Blender, a capture rig (camera, point light, the flat sample) or a mesh scene
(camera, environment, point and area lights, meshes, spheres, quads, their transforms),
puts the woven_import add-on's material on the fabric, and renders linear radiance to an
EXR with Cycles on the CPU.
Blender keeps woven's coordinates as they are (y up); the environment lookup is turned
to match woven's equirectangular convention."""
import argparse
import json
import math
import os
import sys

import bpy
from mathutils import Matrix, Vector

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import woven_import  # noqa: E402


def args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser()
    ap.add_argument("--scene", required=True, help="a woven scene file (capture rig or mesh scene)")
    ap.add_argument("--params", help="the fabric (default: the mesh scene's)")
    ap.add_argument("--env", help="the environment as an EXR (a mesh scene's built-in, written by woven)")
    ap.add_argument("--out", required=True)
    ap.add_argument("--width", type=int, required=True)
    ap.add_argument("--height", type=int, required=True)
    ap.add_argument("--samples", type=int, default=16)
    ap.add_argument("--sheen", type=float, default=0.0)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--save-blend", help="also save the .blend (for screenshots)")
    return ap.parse_args(argv)


def frame(x, y, z, p):
    """The object matrix of axes x, y, z (its local axes in the world) at position p."""
    return Matrix(((x[0], y[0], z[0], p[0]), (x[1], y[1], z[1], p[1]), (x[2], y[2], z[2], p[2]), (0, 0, 0, 1)))


def camera(pos, look, up, vfov_deg):
    cam = bpy.data.cameras.new("camera")
    cam.sensor_fit = "VERTICAL"
    cam.angle_y = math.radians(vfov_deg)
    cam.clip_start, cam.clip_end = 0.01, 1e6
    obj = bpy.data.objects.new("camera", cam)
    bpy.context.scene.collection.objects.link(obj)
    p, z = Vector(pos), -(Vector(look) - Vector(pos)).normalized()  # Blender cameras look down -z
    x = Vector(up).cross(z).normalized()
    y = z.cross(x)
    obj.matrix_world = frame(x, y, z, p)
    bpy.context.scene.camera = obj


def point_light(pos, intensity):
    """woven's point light of radiant intensity I (W/sr): Cycles' point light of power P
    emits P / (4 pi) per steradian, so P = 4 pi I (checked: a white Lambert plane under it
    renders I cos / (pi d^2))."""
    light = bpy.data.lights.new("light", "POINT")
    light.energy = 4 * math.pi * intensity
    light.shadow_soft_size = 0.0
    obj = bpy.data.objects.new("light", light)
    obj.location = pos
    bpy.context.scene.collection.objects.link(obj)


def area_light(pos, look, size, radiance):
    """woven's area light: a one-sided rectangle of constant radiance L (per channel)
    facing look_at, size_mm[0] along e_x = normalize(a x n), size_mm[1] along n x e_x (a
    the y axis, or x when n is nearly along y). Cycles' area light emits along its -z with
    a radiance of P / (4 A) for power P over area A, so P = 4 A L (measured: a white
    Lambert plane under it renders within 1% of woven's, where P = pi A L gave pi / 4 of
    it)."""
    n = (Vector(look) - Vector(pos)).normalized()
    a = Vector((1, 0, 0)) if abs(n.y) > 0.99 else Vector((0, 1, 0))
    ex = a.cross(n).normalized()
    ey = n.cross(ex)
    light = bpy.data.lights.new("area", "AREA")
    light.shape = "RECTANGLE"
    light.size, light.size_y = size[0], size[1]
    top = max(radiance)
    light.color = [c / top for c in radiance] if top > 0 else [0, 0, 0]
    light.energy = 4 * size[0] * size[1] * top
    obj = bpy.data.objects.new("area", light)
    x, y, z = ex, -ey, -n  # local -z along n, a right-handed frame
    obj.matrix_world = frame(x, y, z, pos)
    bpy.context.scene.collection.objects.link(obj)


def transform_matrix(t):
    """woven's object transform: x' = Rz Ry Rx S x + translate_mm (rotate_deg about x, then
    y, then z)."""
    sc = t.get("scale", 1)
    sc = [sc] * 3 if isinstance(sc, (int, float)) else sc
    r = [math.radians(v) for v in t.get("rotate_deg", [0, 0, 0])]
    m = Matrix.Rotation(r[2], 4, "Z") @ Matrix.Rotation(r[1], 4, "Y") @ Matrix.Rotation(r[0], 4, "X") @ \
        Matrix.Diagonal((sc[0], sc[1], sc[2], 1))
    m.translation = Vector(t.get("translate_mm", [0, 0, 0]))
    return m


def mesh_object(name, verts, faces, uvs=None):
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    if uvs:
        layer = me.uv_layers.new(name="UVMap")
        for poly in me.polygons:
            for li in poly.loop_indices:
                layer.data[li].uv = uvs[me.loops[li].vertex_index]
    obj = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def lambert(name, rgb):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (*rgb, 1)
    d.inputs["Roughness"].default_value = 0.0
    o = nt.nodes.new("ShaderNodeOutputMaterial")
    nt.links.new(d.outputs["BSDF"], o.inputs["Surface"])
    return mat


def environment(path, strength):
    """woven's lookup of direction d (y up): column (atan2(d.x, -d.z) + pi) / 2 pi, row
    acos(d.y) / pi from the top. Blender's of b (z up): u = 0.5 - atan2(b.y, b.x) / 2 pi,
    v = 0.5 + asin(b.z) / pi. They agree for b = (-d.z, -d.x, d.y)."""
    world = bpy.data.worlds.new("world")
    bpy.context.scene.world = world
    world.use_nodes = True
    nt = world.node_tree
    nt.nodes.clear()
    tc = nt.nodes.new("ShaderNodeTexCoord")
    sep = nt.nodes.new("ShaderNodeSeparateXYZ")
    neg_x = nt.nodes.new("ShaderNodeMath")
    neg_x.operation = "MULTIPLY"
    neg_x.inputs[1].default_value = -1
    neg_z = nt.nodes.new("ShaderNodeMath")
    neg_z.operation = "MULTIPLY"
    neg_z.inputs[1].default_value = -1
    comb = nt.nodes.new("ShaderNodeCombineXYZ")
    env = nt.nodes.new("ShaderNodeTexEnvironment")
    env.image = bpy.data.images.load(path)
    env.image.colorspace_settings.name = "Linear"
    env.interpolation = "Closest"  # woven looks up the nearest pixel
    bg = nt.nodes.new("ShaderNodeBackground")
    bg.inputs["Strength"].default_value = strength
    out = nt.nodes.new("ShaderNodeOutputWorld")
    L = nt.links
    L.new(tc.outputs["Generated"], sep.inputs["Vector"])
    L.new(sep.outputs["Z"], neg_z.inputs[0])
    L.new(sep.outputs["X"], neg_x.inputs[0])
    L.new(neg_z.outputs[0], comb.inputs["X"])
    L.new(neg_x.outputs[0], comb.inputs["Y"])
    L.new(sep.outputs["Y"], comb.inputs["Z"])
    L.new(comb.outputs["Vector"], env.inputs["Vector"])
    L.new(env.outputs["Color"], bg.inputs["Color"])
    L.new(bg.outputs["Background"], out.inputs["Surface"])


def black_world():
    world = bpy.data.worlds.new("world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    bpy.context.scene.world = world


def capture_rig(s, params, sheen):
    """A capture scene: the plane z = 0 (flat rigs only) under a point light."""
    if s["sample"].get("shape", "plane") != "plane":
        raise SystemExit("only plane capture rigs are rebuilt in Blender")
    camera(s["camera"]["position_mm"], s["camera"]["look_at_mm"], s["camera"].get("up", [0, 1, 0]),
           s["camera"]["vfov_deg"])
    point_light(s["light"]["position_mm"], s["light"]["intensity"])
    black_world()
    side = 4 * s["camera"]["position_mm"][2]  # wider than the view
    h = side / 2
    rot = math.radians(s["sample"].get("rotation_deg", 0))
    c, si = math.cos(rot), math.sin(rot)
    # fabric coordinates (mm) = plane (x, y) turned by the rotation, times mm_per_unit
    corners = [(-h, -h), (h, -h), (h, h), (-h, h)]
    uvs = [((x * c + y * si) / side, (-x * si + y * c) / side) for x, y in corners]
    obj = mesh_object("sample", [(x, y, 0) for x, y in corners], [(0, 1, 2, 3)], uvs)
    mm = s["sample"].get("mm_per_unit", 1.0)
    woven_import.import_capture(params, [obj], uv_mm=side * mm, sheen=sheen)


def mesh_scene(s, scene_path, params, env_path, sheen):
    base = os.path.dirname(os.path.abspath(scene_path))
    c = s["camera"]
    camera(c["position_mm"], c["look_at_mm"], c.get("up", [0, 1, 0]), c["vfov_deg"])
    if "environment" in s:
        environment(env_path, s["environment"].get("strength", 1.0))
    else:
        black_world()
    mats = {}
    for name, m in s["materials"].items():
        if "lambert" in m:
            mats[name] = ("lambert", lambert(name, m["lambert"]))
        else:
            mats[name] = ("fabric", params or os.path.join(base, m["fabric"]), m.get("uv_mm", [1, 1])[0])
    for o in s["objects"]:
        if "mesh" in o:
            before = set(bpy.data.objects)
            bpy.ops.wm.obj_import(filepath=os.path.join(base, o["mesh"]), forward_axis="Y", up_axis="Z")
            objs = [x for x in bpy.data.objects if x not in before]
        elif "sphere" in o:
            bpy.ops.mesh.primitive_uv_sphere_add(segments=96, ring_count=48, radius=o["sphere"]["radius_mm"],
                                                 location=o["sphere"]["centre_mm"])
            bpy.ops.object.shade_smooth()
            objs = [bpy.context.active_object]
        elif "quad" in o:
            q = o["quad"]
            cc, u, v = Vector(q["centre_mm"]), Vector(q["u_axis"]), Vector(q["v_axis"])
            hu, hv = u * q["size_mm"][0] / 2, v * q["size_mm"][1] / 2
            vs = [cc - hu - hv, cc + hu - hv, cc + hu + hv, cc - hu + hv]
            objs = [mesh_object("quad", [tuple(p) for p in vs], [(0, 1, 2, 3)], [(0, 0), (1, 0), (1, 1), (0, 1)])]
        else:
            raise SystemExit(f"object {o} is not rebuilt in Blender")
        if "transform" in o:
            for obj in objs:
                obj.matrix_world = transform_matrix(o["transform"]) @ obj.matrix_world
        kind = mats[o["material"]]
        for obj in objs:
            if kind[0] == "lambert":
                obj.data.materials.clear()
                obj.data.materials.append(kind[1])
        if kind[0] == "fabric":
            woven_import.import_capture(kind[1], objs, uv_mm=kind[2], sheen=sheen)
    for lt in s.get("lights", []):
        if lt.get("type", "point") == "point":
            point_light(lt["position_mm"], lt["intensity"])
        elif lt["type"] == "area":
            r = lt["radiance"]
            area_light(lt["position_mm"], lt["look_at_mm"], lt["size_mm"], [r] * 3 if isinstance(r, (int, float)) else r)
        else:
            raise SystemExit(f"light {lt} is not rebuilt in Blender")
    return s.get("render", {}).get("max_bounces", 3)


def main():
    a = args()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    with open(a.scene) as f:
        s = json.load(f)
    sc = bpy.context.scene
    bounces = 0
    if "objects" in s:
        bounces = mesh_scene(s, a.scene, a.params, a.env, a.sheen)
    else:
        capture_rig(s, a.params, a.sheen)
    sc.render.engine = "CYCLES"
    sc.cycles.device = "CPU"
    sc.cycles.samples = a.samples
    sc.cycles.use_denoising = False
    sc.cycles.use_adaptive_sampling = False
    sc.cycles.max_bounces = bounces
    sc.cycles.diffuse_bounces = sc.cycles.glossy_bounces = bounces
    sc.cycles.pixel_filter_type = "BOX"  # woven averages samples over the pixel's square
    sc.cycles.filter_width = 1.0
    sc.cycles.sample_clamp_direct = sc.cycles.sample_clamp_indirect = 0.0
    sc.render.threads_mode = "FIXED"
    sc.render.threads = a.threads
    sc.render.resolution_x, sc.render.resolution_y, sc.render.resolution_percentage = a.width, a.height, 100
    sc.render.film_transparent = False
    sc.view_settings.view_transform = "Standard"
    sc.view_settings.look = "None"
    sc.render.image_settings.file_format = "OPEN_EXR"
    sc.render.image_settings.color_depth = "32"
    sc.render.image_settings.color_mode = "RGB"
    sc.render.filepath = a.out
    if a.save_blend:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(a.save_blend))
    bpy.ops.render.render(write_still=True)


main()
