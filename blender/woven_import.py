"""woven capture import for Blender (3.4+): a capture directory (woven capture / woven fit)
or a params.json becomes a node material driven by woven's tileable maps (woven maps),
at the capture's physical scale on any UV-mapped mesh.

The material: a Principled BSDF carries woven's diffuse lobe (k_d from diffuse.png, the
yarn normals from normal.png blended with the surface normal by the diffuse blend w)
and a sheen; an anisotropic Glossy BSDF carries woven's fibre specular (k_s from
specular.png, which is an RGB colour the Principled specular cannot hold), with its
roughness along the fibre tangent (tangent.png, turned into world space through the
mesh's UV tangents) from woven's SGGX alpha and wide across it, as a fibre's highlight
spreads across its length. Light through the cloth: a Translucent BSDF carries woven's
diffuse transmission (transmission.png: k_t + k_f times the cloth's diffuse transmittance), and the
open gaps between yarns (open.png) are a Transparent BSDF: they reflect nothing and let the
light behind the cloth straight through.
Install: Edit > Preferences > Add-ons > Install... and pick this file; then
File > Import > woven capture. See docs/blender.md."""

bl_info = {
    "name": "woven capture import",
    "author": "woven",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "File > Import > woven capture (params.json or capture directory)",
    "description": "Imports a woven fabric capture as a node material at its physical scale",
    "category": "Import-Export",
}

import json
import math
import os
import shutil
import subprocess
import tempfile

import bpy
from bpy.props import FloatProperty, IntProperty, StringProperty
from bpy_extras.io_utils import ImportHelper

MAPS = ("normal", "tangent", "yarn_id", "diffuse", "specular", "roughness", "transmission", "open")


class WovenImportError(Exception):
    pass


def woven_binary():
    prefs = bpy.context.preferences.addons.get(__name__)
    exe = (prefs.preferences.woven_binary if prefs else "") or os.environ.get("WOVEN_BINARY") or "woven"
    found = shutil.which(exe)
    if not found:
        raise WovenImportError(f"the woven program '{exe}' was not found: set its path in the add-on's preferences")
    return found


def find_capture(path, size=1024):
    """(params.json, maps directory, maps.json content) of a capture directory or a
    parameter file; maps are made with `woven maps` when the capture has none."""
    path = os.path.abspath(bpy.path.abspath(path))
    if os.path.isdir(path):
        params = os.path.join(path, "params.json")
    else:
        params = path
    if not os.path.isfile(params):
        raise WovenImportError(f"{params}: no woven parameter file (a capture directory holds params.json)")
    maps = os.path.join(os.path.dirname(params), "maps")
    if not all(os.path.isfile(os.path.join(maps, f"{m}.png")) for m in MAPS) or \
            not os.path.isfile(os.path.join(maps, "maps.json")):
        maps = os.path.join(tempfile.mkdtemp(prefix="woven-maps-"), "maps")
        r = subprocess.run([woven_binary(), "maps", "--params", params, "--size", str(size), "--format", "png",
                            "-o", maps, "--quiet"], capture_output=True, text=True)
        if r.returncode:
            raise WovenImportError(r.stderr.strip() or f"woven maps failed (exit {r.returncode})")
    with open(os.path.join(maps, "maps.json")) as f:
        meta = json.load(f)
    with open(params) as f:
        p = json.load(f)
    return params, maps, meta, p


def uv_mm_of(obj):
    """Millimetres of fabric per UV unit that keep a mesh's texture at its physical size:
    the square root of the ratio of its world area (Blender units as metres, times the
    scene's unit scale) to its UV area."""
    me = obj.data
    if not me.uv_layers:
        raise WovenImportError(f"{obj.name} has no UV map")
    uv = me.uv_layers.active.data
    world, uvarea = 0.0, 0.0
    mw = obj.matrix_world
    for poly in me.polygons:
        idx = list(poly.loop_indices)
        p0 = mw @ me.vertices[me.loops[idx[0]].vertex_index].co
        u0 = uv[idx[0]].uv
        for a, b in zip(idx[1:-1], idx[2:]):
            pa, pb = mw @ me.vertices[me.loops[a].vertex_index].co, mw @ me.vertices[me.loops[b].vertex_index].co
            world += (pa - p0).cross(pb - p0).length / 2
            ua, ub = uv[a].uv - u0, uv[b].uv - u0
            uvarea += abs(ua.x * ub.y - ua.y * ub.x) / 2
    if uvarea <= 0:
        raise WovenImportError(f"{obj.name}: its UV map covers no area")
    scale = bpy.context.scene.unit_settings.scale_length * 1000.0  # mm per Blender unit
    return math.sqrt(world / uvarea) * scale


def build_material(name, maps, meta, params, uv_mm, sheen=0.0):
    """The node material of one capture; uv_mm: millimetres of fabric per UV unit."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.clear()
    N, L = nt.nodes, nt.links

    def node(kind, x, y, **attrs):
        n = N.new(kind)
        n.location = (x, y)
        for k, v in attrs.items():
            setattr(n, k, v)
        return n

    def math_node(op, a, b=None, x=0, y=0, vector=False):
        n = node("ShaderNodeVectorMath" if vector else "ShaderNodeMath", x, y, operation=op)
        for i, v in enumerate((a, b)):
            if v is None:
                continue
            if isinstance(v, bpy.types.NodeSocket):
                L.new(v, n.inputs[i])
            elif vector:
                n.inputs[i].default_value = (v, v, v)
            else:
                n.inputs[i].default_value = v
        return n.outputs["Vector" if vector else "Value"]

    tile = meta["tile_mm"]
    uvn = node("ShaderNodeUVMap", -1600, 0)
    mapping = node("ShaderNodeMapping", -1400, 0)
    mapping.inputs["Scale"].default_value = (uv_mm / tile[0], uv_mm / tile[1], 1.0)
    L.new(uvn.outputs["UV"], mapping.inputs["Vector"])
    tex = {}
    for i, m in enumerate(MAPS):
        t = node("ShaderNodeTexImage", -1150, 500 - 280 * i, label=m, interpolation="Linear", extension="REPEAT")
        t.image = bpy.data.images.load(os.path.join(maps, f"{m}.png"), check_existing=False)
        t.image.name = f"{name} {m}"
        t.image.pack()  # the material survives the maps' folder
        # albedos are sRGB-encoded in the PNGs; vectors, ids and alpha are data
        t.image.colorspace_settings.name = "sRGB" if m in ("diffuse", "specular", "transmission") else "Non-Color"
        L.new(mapping.outputs["Vector"], t.inputs["Vector"])
        tex[m] = t

    # coverage: 1 on a yarn (warp R or weft G), 0 in a gap
    ids = node("ShaderNodeSeparateColor", -850, -900)
    L.new(tex["yarn_id"].outputs["Color"], ids.inputs["Color"])
    cover = math_node("ADD", ids.outputs[0], ids.outputs[1], -650, -900)
    cover.node.use_clamp = True

    def covered(colour, y):
        mix = node("ShaderNodeMix", -450, y, data_type="RGBA", blend_type="MULTIPLY")
        mix.inputs["Factor"].default_value = 1.0
        L.new(colour, mix.inputs[6])
        L.new(cover, mix.inputs[7])
        return mix.outputs[2]

    kd = covered(tex["diffuse"].outputs["Color"], 500)
    ks = covered(tex["specular"].outputs["Color"], 200)

    # normals: the yarn normal for the specular; blended with the surface's by w for the diffuse
    nmap_s = node("ShaderNodeNormalMap", -650, -200, space="TANGENT")
    L.new(tex["normal"].outputs["Color"], nmap_s.inputs["Color"])
    nmap_d = node("ShaderNodeNormalMap", -650, -400, space="TANGENT")
    nmap_d.inputs["Strength"].default_value = float(params.get("diffuse_blend", 0.5))
    L.new(tex["normal"].outputs["Color"], nmap_d.inputs["Color"])

    # the fibre tangent in world space: t.x T + t.y B + t.z N (T along u, B = N x T along v)
    tvec = math_node("MULTIPLY_ADD", tex["tangent"].outputs["Color"], 2.0, -850, -600, vector=True)
    tvec.node.inputs[2].default_value = (-1.0, -1.0, -1.0)
    tsep = node("ShaderNodeSeparateXYZ", -650, -600)
    L.new(tvec, tsep.inputs["Vector"])
    tan = node("ShaderNodeTangent", -850, -1100, direction_type="UV_MAP")
    geo = node("ShaderNodeNewGeometry", -850, -1300)
    bit = math_node("CROSS_PRODUCT", geo.outputs["Normal"], tan.outputs["Tangent"], -650, -1100, vector=True)
    parts = []
    for k, axis in enumerate((tan.outputs["Tangent"], bit, geo.outputs["Normal"])):
        s = node("ShaderNodeVectorMath", -450, -1000 - 150 * k, operation="SCALE")
        L.new(axis, s.inputs[0])
        L.new(tsep.outputs[k], s.inputs["Scale"])
        parts.append(s.outputs["Vector"])
    fibre = math_node("ADD", math_node("ADD", parts[0], parts[1], -300, -1050, vector=True), parts[2], -150, -1100,
                      vector=True)
    fibre = math_node("NORMALIZE", fibre, None, 0, -1100, vector=True)

    # GGX alpha = roughness^2: along the fibre woven's SGGX alpha, across it 1 (a fibre's
    # highlight spreads across its length): roughness r = alpha^(1/4), anisotropy 1 - r
    # (Cycles: r (1 - a) along the tangent, r / (1 - a) across it).
    alpha = tex["roughness"].outputs["Color"]
    r = math_node("POWER", alpha, 0.25, -650, 0)
    aniso = math_node("SUBTRACT", 1.0, r, -450, 0)

    gloss = node("ShaderNodeBsdfAnisotropic", 200, 0, distribution="GGX")
    L.new(ks, gloss.inputs["Color"])
    L.new(r, gloss.inputs["Roughness"])
    L.new(aniso, gloss.inputs["Anisotropy"])
    L.new(nmap_s.outputs["Normal"], gloss.inputs["Normal"])
    L.new(fibre, gloss.inputs["Tangent"])

    pr = node("ShaderNodeBsdfPrincipled", 200, 500)
    L.new(kd, pr.inputs["Base Color"])
    pr.inputs["Specular"].default_value = 0.0  # the fibre specular is the Glossy lobe
    pr.inputs["Roughness"].default_value = 1.0
    pr.inputs["Sheen"].default_value = sheen
    pr.inputs["Sheen Tint"].default_value = 0.5
    L.new(nmap_d.outputs["Normal"], pr.inputs["Normal"])
    L.new(fibre, pr.inputs["Tangent"])

    add = node("ShaderNodeAddShader", 500, 200)
    L.new(pr.outputs["BSDF"], add.inputs[0])
    L.new(gloss.outputs["BSDF"], add.inputs[1])

    # light through the yarns: woven's diffuse transmission k_t F_t, F_t = (w cos_b + (1 - w)
    # |mu_i|) / pi times the cloth's diffuse transmittance (the map holds k_t + k_f times it: the
    # forward band's light, at normal incidence, spread out diffusely), cos_b
    # on the yarn's underside, the mirror of its top: a Translucent BSDF (cos / pi toward the
    # far side) on the diffuse lobe's blended normal
    trans = node("ShaderNodeBsdfTranslucent", 200, -300)
    L.new(tex["transmission"].outputs["Color"], trans.inputs["Color"])
    L.new(nmap_d.outputs["Normal"], trans.inputs["Normal"])
    add_t = node("ShaderNodeAddShader", 700, 0)
    L.new(add.outputs["Shader"], add_t.inputs[0])
    L.new(trans.outputs["BSDF"], add_t.inputs[1])
    # open gaps: no yarn, so nothing reflected and the light behind seen straight through
    gap = node("ShaderNodeBsdfTransparent", 700, -250)
    opening = node("ShaderNodeMixShader", 900, 0)
    L.new(tex["open"].outputs["Color"], opening.inputs["Fac"])
    L.new(add_t.outputs["Shader"], opening.inputs[1])
    L.new(gap.outputs["BSDF"], opening.inputs[2])
    out = node("ShaderNodeOutputMaterial", 1100, 0, target="CYCLES")
    L.new(opening.outputs["Shader"], out.inputs["Surface"])
    mat["woven"] = {"tile_mm": list(tile), "uv_mm": uv_mm, "params": json.dumps(params)}
    return mat


def import_capture(path, objects, uv_mm=0.0, sheen=0.0, size=1024):
    """Builds the material of a capture and assigns it to objects (UV-mapped meshes).
    uv_mm 0: each object's own physical scale (uv_mm_of). Returns the materials."""
    params_path, maps, meta, params = find_capture(path, size)
    label = os.path.basename(os.path.dirname(params_path)) if os.path.isdir(path) else \
        os.path.splitext(os.path.basename(params_path))[0]
    mats = []
    for obj in objects:
        scale = uv_mm if uv_mm > 0 else uv_mm_of(obj)
        mat = build_material(f"woven {label}", maps, meta, params, scale, sheen)
        obj.data.materials.clear()
        obj.data.materials.append(mat)
        mats.append(mat)
    return mats


class ImportWovenCapture(bpy.types.Operator, ImportHelper):
    """Import a woven capture (a capture directory or params.json) as a fabric material
    on the selected meshes (a 100 mm square when none is selected)"""
    bl_idname = "import_scene.woven_capture"
    bl_label = "Import woven capture"
    bl_options = {"REGISTER", "UNDO"}
    filename_ext = ".json"
    filter_glob: StringProperty(default="*.json", options={"HIDDEN"})
    uv_mm: FloatProperty(name="UV unit (mm)", default=0.0, min=0.0,
                         description="millimetres of fabric per UV unit (0: from each mesh's size)")
    sheen: FloatProperty(name="Sheen", default=0.0, min=0.0, max=1.0)
    map_size: IntProperty(name="Map size", default=1024, min=16, max=8192,
                          description="pixels per tile side when the maps are made")

    def execute(self, context):
        objs = [o for o in context.selected_objects if o.type == "MESH"]
        try:
            if not objs:
                bpy.ops.mesh.primitive_plane_add(size=0.1 / context.scene.unit_settings.scale_length)
                objs = [context.active_object]
            import_capture(self.filepath, objs, self.uv_mm, self.sheen, self.map_size)
        except WovenImportError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        return {"FINISHED"}


class WovenPreferences(bpy.types.AddonPreferences):
    bl_idname = __name__
    woven_binary: StringProperty(name="woven program", subtype="FILE_PATH", default="",
                                 description="the woven binary (makes the maps of a bare params.json)")

    def draw(self, context):
        self.layout.prop(self, "woven_binary")


def menu(self, context):
    self.layout.operator(ImportWovenCapture.bl_idname, text="woven capture (params.json / capture dir)")


def register():
    bpy.utils.register_class(WovenPreferences)
    bpy.utils.register_class(ImportWovenCapture)
    bpy.types.TOPBAR_MT_file_import.append(menu)


def unregister():
    bpy.types.TOPBAR_MT_file_import.remove(menu)
    bpy.utils.unregister_class(ImportWovenCapture)
    bpy.utils.unregister_class(WovenPreferences)
