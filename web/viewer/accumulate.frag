// woven viewer: progressive accumulation, sum = previous sum + this frame's mean.
precision highp float;
uniform sampler2D uPrev, uCurrent;
uniform float uKeep; // 0 on the first frame
out vec4 outColor;
void main() {
  ivec2 p = ivec2(gl_FragCoord.xy);
  outColor = uKeep * texelFetch(uPrev, p, 0) + texelFetch(uCurrent, p, 0);
}
