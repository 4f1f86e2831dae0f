// Usage: node draco_check.mjs FILE.glb|FILE.gltf|FILE.drc... -> JSON array. For .drc: the decoded
// counts and bounds. For glTF: every KHR_draco_mesh_compression primitive decoded with draco3d and
// compared with its accessors (problems lists every mismatch).
import fs from 'node:fs';
import { decodeDraco, checkDracoGltf } from './lib.mjs';

const results = [];
for (const file of process.argv.slice(2)) {
  if (file.toLowerCase().endsWith('.drc')) {
    const d = await decodeDraco(fs.readFileSync(file));
    results.push({ file, ...d, problems: d.ok ? [] : [d.error] });
  } else {
    results.push(await checkDracoGltf(file));
  }
}
process.stdout.write(JSON.stringify(results) + '\n');
