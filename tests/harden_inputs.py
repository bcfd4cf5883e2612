#!/usr/bin/env python3
# Hostile files for tests/cli_harden.sh (the mesh renderer's inputs): meshes with huge
# coordinates or UVs, a glTF whose node tree is DEPTH deep, PLY headers and a GLB chunk
# declaring far more than the file holds, EXR maps (written here, uncompressed) with
# huge values, and scene files naming them.
# Usage: harden_inputs.py DIR FABRIC.json
import json, struct, base64, os, sys
d = sys.argv[1]
os.makedirs(d, exist_ok=True)
def w(name, data, mode='w'):
    with open(os.path.join(d, name), mode) as f: f.write(data)
def exr(name, W, H, val):
    def attr(n, t, v): return n.encode()+b'\0'+t.encode()+b'\0'+struct.pack('<i', len(v))+v
    ch = b''.join(c.encode()+b'\0'+struct.pack('<iBBBBii', 2, 0, 0, 0, 0, 1, 1) for c in 'BGR')+b'\0'
    hdr = b'\x76\x2f\x31\x01'+struct.pack('<i', 2)
    hdr += attr('channels', 'chlist', ch)+attr('compression', 'compression', b'\0')
    box = struct.pack('<iiii', 0, 0, W-1, H-1)
    hdr += attr('dataWindow', 'box2i', box)+attr('displayWindow', 'box2i', box)
    hdr += attr('lineOrder', 'lineOrder', b'\0')+attr('pixelAspectRatio', 'float', struct.pack('<f', 1))
    hdr += attr('screenWindowCenter', 'v2f', struct.pack('<ff', 0, 0))+attr('screenWindowWidth', 'float', struct.pack('<f', 1))+b'\0'
    line = struct.pack('<f', val)*(W*3)
    blk = 8+len(line)
    off0 = len(hdr)+8*H
    with open(os.path.join(d, name), 'wb') as f:
        f.write(hdr)
        f.write(b''.join(struct.pack('<Q', off0+y*blk) for y in range(H)))
        for y in range(H): f.write(struct.pack('<ii', y, len(line))+line)
# a quad as an OBJ with given coordinate scale and UV scale
def quad(name, s=100.0, uv=1.0):
    w(name, f"v {-s} 0 {-s}\nv {s} 0 {-s}\nv {s} 0 {s}\nv {-s} 0 {s}\nvt 0 0\nvt {uv} 0\nvt {uv} {uv}\nvt 0 {uv}\nvn 0 1 0\nf 1/1/1 4/4/1 3/3/1\nf 1/1/1 3/3/1 2/2/1\n")
quad('quad.obj'); quad('uv1e20.obj', 100, 1e20); quad('c1e10.obj', 1e10); quad('c3e38.obj', 3e38)
# deep glTF: a chain of nodes, the last holds a triangle
pos = struct.pack('<9f', 0,0,0, 1,0,0, 0,1,0); uvb = struct.pack('<6f', 0,0, 1,0, 0,1)
buf = pos+uvb
N = int(os.environ.get('DEPTH', '20000'))
nodes = [{"children": [i+1]} for i in range(N-1)]+[{"mesh": 0}]
g = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": nodes,
     "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}]}],
     "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64,"+base64.b64encode(buf).decode()}],
     "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
     "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
                   {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}]}
w('deep.gltf', json.dumps(g, separators=(',', ':')))
g2 = dict(g); g2['nodes'] = [{"mesh": 0}]
w('tri.gltf', json.dumps(g2))
# PLY bombs
w('bomb.ply', "ply\nformat ascii 1.0\nelement vertex 2000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n")
w('bombbin.ply', b"ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nproperty float x\nproperty float y\nproperty float z\nproperty float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" + b'\0'*48, 'wb')
# GLB with a huge chunk length
js = json.dumps(g2).encode(); js += b' '*((4-len(js) % 4) % 4)
glb = struct.pack('<4sII', b'glTF', 2, 0) + struct.pack('<I4s', len(js), b'JSON') + js + struct.pack('<I4s', 0x7ffffff0, b'BIN\0') + b'\0'*64
glb = glb[:8]+struct.pack('<I', len(glb))+glb[12:]
w('bomb.glb', glb, 'wb')
exr('env.exr', 8, 4, 1.0); exr('envhuge.exr', 8, 4, 3.4e38); exr('map.exr', 64, 32, 0.5)
fab = os.path.abspath(sys.argv[2])
def scene(name, objs, mats=None, env=None, edits=None, limits=None):
    s = {"image": {"width": 32, "height": 24, "spp": 1}, "camera": {"position_mm": [0, 300, 300], "look_at_mm": [0, 0, 0], "vfov_deg": 40},
         "environment": env or {"builtin": "white", "width": 16},
         "materials": mats or {"cloth": {"fabric": fab}}, "objects": objs}
    if edits: s["edits"] = edits
    if limits: s["limits"] = limits
    w(name, json.dumps(s))
scene('s_deep.json', [{"mesh": "deep.gltf", "material": "grey"}], {"grey": {"lambert": 0.5}})
scene('s_bomb.json', [{"mesh": "bomb.ply", "material": "grey"}], {"grey": {"lambert": 0.5}})
scene('s_bombbin.json', [{"mesh": "bombbin.ply", "material": "grey"}], {"grey": {"lambert": 0.5}})
scene('s_glb.json', [{"mesh": "bomb.glb", "material": "grey"}], {"grey": {"lambert": 0.5}})
scene('s_raise.json', [{"mesh": "bomb.ply", "material": "grey"}], {"grey": {"lambert": 0.5}}, limits={"mesh_mb": 1048576})
scene('s_uv.json', [{"mesh": "uv1e20.obj", "material": "cloth"}])
scene('s_c1e10.json', [{"mesh": "c1e10.obj", "material": "cloth"}])
scene('s_c3e38.json', [{"mesh": "c3e38.obj", "material": "cloth"}])
scene('s_env.json', [{"mesh": "quad.obj", "material": "cloth"}], env={"file": "envhuge.exr", "strength": 1e6})
scene('s_ok.json', [{"mesh": "quad.obj", "material": "cloth"}], env={"file": "env.exr"},
      edits=[{"material": "cloth", "apply": "roughness", "map": "map.exr"}])
scene('s_edits8.json', [{"mesh": "quad.obj", "material": "cloth"}],
      edits=[{"material": "cloth", "apply": "roughness", "map": "map.exr" if i % 2 else "maplink.exr"} for i in range(8)])
scene('s_fifo_map.json', [{"mesh": "quad.obj", "material": "cloth"}], edits=[{"material": "cloth", "apply": "roughness", "map": "fifo"}])
scene('s_fifo_env.json', [{"mesh": "quad.obj", "material": "cloth"}], env={"file": "fifo"})
scene('s_fifo_fab.json', [{"mesh": "quad.obj", "material": "cloth"}], {"cloth": {"fabric": "fifo"}})
scene('s_passwd.json', [{"mesh": "quad.obj", "material": "cloth"}], {"cloth": {"fabric": "/etc/passwd"}})
scene('s_tri.json', [{"mesh": "tri.gltf", "material": "grey"}], {"grey": {"lambert": 0.5}})
scene('s_link.json', [{"mesh": "lnk.obj", "material": "cloth"}])
