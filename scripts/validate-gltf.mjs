// Validates glTF / .glb files with the Khronos glTF validator (npm package gltf-validator).
// Usage: node scripts/validate-gltf.mjs FILE...
// The package is resolved from $GLTF_VALIDATOR_DIR/node_modules when set (install it there with
// `npm install --prefix DIR gltf-validator@2.0.0-dev.3.10`), else next to this script.
// Prints one summary line per file plus every error and warning; exits 1 if any file has errors.
import { createRequire } from 'node:module';
import { readFileSync } from 'node:fs';
import path from 'node:path';

const base = process.env.GLTF_VALIDATOR_DIR
  ? path.join(path.resolve(process.env.GLTF_VALIDATOR_DIR), 'resolve-from-here.js')
  : import.meta.url;
const validator = createRequire(base)('gltf-validator');

let errors = 0;
for (const file of process.argv.slice(2)) {
  const report = await validator.validateBytes(new Uint8Array(readFileSync(file)), { maxIssues: 200 });
  const i = report.issues;
  console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints`);
  for (const m of i.messages) {
    if (m.severity <= 1) {
      console.log(`  [${m.severity === 0 ? 'error' : 'warning'}] ${m.code}: ${m.message} ${m.pointer ?? ''}`);
    }
  }
  errors += i.numErrors;
}
process.exit(errors > 0 ? 1 : 0);
