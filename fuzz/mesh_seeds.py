#!/usr/bin/env python3
# Seeds for the mesh_check and mesh harnesses (first byte: the extension, see the
# harnesses): a glTF whose node tree is deeper than woven reads, one just within it,
# PLY headers (ascii and binary) declaring more than the file holds, a GLB whose
# binary chunk claims more bytes than the file has, a binary STL, and a glTF with an
# external buffer. Usage: mesh_seeds.py DIR [DIR...]
import base64, json, os, struct, sys

def gltf(depth, acc_count=3, uri=None):
    buf = struct.pack('<9f', 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack('<6f', 0, 0, 1, 0, 0, 1)
    nodes = [{"children": [i + 1]} for i in range(depth - 1)] + [{"mesh": 0}]
    b = {"byteLength": len(buf)}
    if uri != "":
        b["uri"] = uri or "data:application/octet-stream;base64," + base64.b64encode(buf).decode()
    return {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": nodes,
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}}]}],
            "buffers": [b],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3"},
                          {"bufferView": 1, "componentType": 5126, "count": acc_count, "type": "VEC2"}]}, buf

def glb(g, buf, chunk_len=None):
    js = json.dumps(g).encode()
    js += b' ' * ((4 - len(js) % 4) % 4)
    body = struct.pack('<I4s', len(js), b'JSON') + js + struct.pack('<I4s', chunk_len or len(buf), b'BIN\0') + buf
    return struct.pack('<4sII', b'glTF', 2, 12 + len(body)) + body

seeds = {
    'deep.gltf': b'n' + json.dumps(gltf(300)[0], separators=(',', ':')).encode(),
    'deep256.gltf': b'n' + json.dumps(gltf(256)[0], separators=(',', ':')).encode(),
    'tri.gltf': b'n' + json.dumps(gltf(1)[0]).encode(),
    'acc.gltf': b'n' + json.dumps(gltf(1, 2**31 - 1)[0]).encode(),
    'ext.gltf': b'n' + json.dumps(gltf(1, uri="b.bin")[0]).encode(),
    'tri.glb': b'o' + glb(gltf(1, uri="")[0], gltf(1)[1]),
    'chunk.glb': b'o' + glb(gltf(1, uri="")[0], gltf(1)[1], 0x7ffffff0),
    'bomb.ply': b'm' + b"ply\nformat ascii 1.0\nelement vertex 2000000000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n",
    'bombbin.ply': b'm' + b"ply\nformat binary_little_endian 1.0\nelement vertex 20000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" + b'\0' * 48,
    'tri.stl': b'p' + b'\0' * 80 + struct.pack('<I', 1) + b'\0' * 50,
}
for d in sys.argv[1:]:
    os.makedirs(d, exist_ok=True)
    for name, data in seeds.items():
        if os.path.basename(d.rstrip('/')) == 'mesh':  # the mesh harness: 2 bits pick the extension
            if name.endswith('.stl'):
                continue
        with open(os.path.join(d, name), 'wb') as f:
            f.write(data)
