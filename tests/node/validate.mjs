// Validates a glTF binary with the Khronos glTF-Validator (the npm package `gltf-validator`)
// and prints its report as JSON on stdout. Usage: node validate.mjs FILE.glb
// Exit status: 0 when the validator ran (whatever it found; the caller reads the counts),
// 2 when it could not run (missing argument, unreadable file, validator exception).
import { readFile } from 'node:fs/promises';
import validator from 'gltf-validator';

const file = process.argv[2];
if (!file) {
  console.error('usage: node validate.mjs FILE.glb');
  process.exit(2);
}
try {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: file,
    maxIssues: 0,
    // Every issue counts: nothing is ignored or downgraded.
    externalResourceFunction: () => Promise.reject(new Error('no external resources')),
  });
  console.log(JSON.stringify(report, null, 2));
} catch (e) {
  console.error(`gltf-validator failed on ${file}: ${e}`);
  process.exit(2);
}
