// Checks the material wiring the page of `twopass view` relies on in a lightmapped glTF
// asset, reading the .glb's JSON as the page's GLTFLoader does, and prints a JSON summary:
// { "primitives": n, "materials": n, "problems": [...] }. Every primitive of every mesh a node
// shows must have TEXCOORD_1 and a material whose extras.lightMap names an embedded PNG
// texture on texCoord 1, with a finite positive intensity and, for RGBM, a multiplier.
// Usage: node lightmap_wiring.mjs FILE.glb. Exit status 0 when it ran (the caller reads the
// problems), 2 when the file cannot be read as a glTF binary.
import { readFile } from 'node:fs/promises';

const file = process.argv[2];
let doc;
try {
  const bytes = await readFile(file);
  if (bytes.toString('latin1', 0, 4) !== 'glTF') throw new Error('not a glTF binary');
  const length = bytes.readUInt32LE(12);
  doc = JSON.parse(bytes.toString('utf8', 20, 20 + length));
} catch (e) {
  console.error(`cannot read ${file}: ${e}`);
  process.exit(2);
}
const problems = [];
const materials = new Set();
let primitives = 0;
for (const node of doc.nodes ?? []) {
  if (node.mesh === undefined) continue;
  doc.meshes[node.mesh].primitives.forEach((p, i) => {
    primitives += 1;
    const at = `node ${node.name}, primitive ${i}`;
    if (p.attributes.TEXCOORD_1 === undefined) problems.push(`${at}: no TEXCOORD_1`);
    const m = doc.materials?.[p.material];
    const entry = m?.extras?.lightMap;
    if (!entry) {
      problems.push(`${at}: its material has no extras.lightMap`);
      return;
    }
    materials.add(p.material);
    if (entry.texCoord !== 1) problems.push(`${at}: texCoord ${entry.texCoord}`);
    const texture = doc.textures?.[entry.index];
    const image = doc.images?.[texture?.source];
    if (image?.mimeType !== 'image/png' || image.bufferView === undefined) {
      problems.push(`${at}: lightMap texture ${entry.index} is not an embedded PNG`);
    }
    if (!(Number.isFinite(entry.intensity) && entry.intensity > 0)) {
      problems.push(`${at}: intensity ${entry.intensity}`);
    }
    if (entry.encoding === 'rgbm') {
      if (!(Number.isFinite(entry.multiplier) && entry.multiplier > 0)) {
        problems.push(`${at}: RGBM multiplier ${entry.multiplier}`);
      }
    } else if (entry.encoding !== 'srgb') {
      problems.push(`${at}: encoding ${entry.encoding}`);
    }
  });
}
console.log(JSON.stringify({ primitives, materials: materials.size, problems }));
