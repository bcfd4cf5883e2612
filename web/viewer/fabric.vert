// woven viewer: the fabric pass's vertex shader (world position and the mesh's
// frame for fabric.frag).
precision highp float;
in vec3 position;
in vec3 normal;
in vec4 tangent;
in vec2 uv;
uniform mat4 modelMatrix, viewMatrix, projectionMatrix;
out vec3 vWorld;
out vec3 vNormal;
out vec4 vTangent;
out vec2 vUv;
void main() {
  vec4 w = modelMatrix * vec4(position, 1.0);
  vWorld = w.xyz;
  vNormal = mat3(modelMatrix) * normal;
  vTangent = vec4(mat3(modelMatrix) * tangent.xyz, tangent.w);
  vUv = uv;
  gl_Position = projectionMatrix * viewMatrix * w;
}
