// Validates a .glb with the Khronos glTF validator; prints its summary as JSON
// and exits 1 when it reports an error. Usage: node validate_gltf.mjs FILE.glb
import { readFileSync } from 'node:fs';
import { validateBytes } from 'gltf-validator';

const file = process.argv[2];
if (!file) {
  console.error('usage: node validate_gltf.mjs FILE.glb');
  process.exit(2);
}
const report = await validateBytes(new Uint8Array(readFileSync(file)), { uri: file, maxIssues: 200 });
const issues = report.issues;
console.log(JSON.stringify({
  file,
  validator: report.validatorVersion,
  errors: issues.numErrors, warnings: issues.numWarnings, infos: issues.numInfos, hints: issues.numHints,
  messages: issues.messages.map((m) => `${['error', 'warning', 'info', 'hint'][m.severity]} ${m.code} ${m.pointer ?? ''}: ${m.message}`),
  extensions: report.info?.extensionsUsed,
}, null, 1));
process.exit(issues.numErrors > 0 ? 1 : 0);
