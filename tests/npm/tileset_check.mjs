// Usage: node tileset_check.mjs DIR... -> JSON array, one structural check of DIR/tileset.json each:
// 3D Tiles 1.1 asset, refine on the root, geometricError never growing from parent to child (and
// from the tileset to the root), every child box inside its parent's, every content URI present,
// valid for the Khronos glTF validator (Draco primitives decoded and checked too) and inside its
// tile's box (glTF y-up rotated to the tileset's z-up as 3D Tiles clients do).
import fs from 'node:fs';
import path from 'node:path';
import { validateFile, readGltf, checkDracoGltf } from './lib.mjs';

// Axis-aligned boxes only (what libmrtile writes): returns {min, max} or null.
function aabb(box) {
  const [cx, cy, cz, ux, uy, uz, vx, vy, vz, wx, wy, wz] = box;
  if (uy || uz || vx || vz || wx || wy) return null;
  const h = [Math.abs(ux), Math.abs(vy), Math.abs(wz)];
  return { min: [cx - h[0], cy - h[1], cz - h[2]], max: [cx + h[0], cy + h[1], cz + h[2]] };
}

function inside(inner, outer, tolerance) {
  for (let k = 0; k < 3; ++k)
    if (inner.min[k] < outer.min[k] - tolerance || inner.max[k] > outer.max[k] + tolerance) return false;
  return true;
}

async function checkTileset(dir) {
  const problems = [];
  const validation = [];
  const draco = [];
  const file = path.join(dir, 'tileset.json');
  const tileset = JSON.parse(fs.readFileSync(file, 'utf8'));
  if (!tileset.asset || tileset.asset.version !== '1.1') problems.push('asset.version is not "1.1"');
  if (typeof tileset.geometricError !== 'number') problems.push('no top-level geometricError');
  const root = tileset.root;
  if (!root) return { dir, problems: ['no root'] };
  if (root.refine !== 'REPLACE' && root.refine !== 'ADD') problems.push('root has no refine');
  if (root.geometricError > tileset.geometricError) problems.push('root geometricError exceeds the tileset geometricError');
  let tiles = 0;
  let contents = 0;
  const walk = async (tile, where, parent) => {
    ++tiles;
    if (!(tile.geometricError >= 0)) problems.push(`${where}: geometricError missing or negative`);
    const box = tile.boundingVolume && tile.boundingVolume.box;
    const bounds = box && box.length === 12 ? aabb(box) : null;
    if (!bounds) problems.push(`${where}: boundingVolume.box missing or not axis-aligned`);
    const size = bounds ? Math.max(1, ...bounds.max.map((v, k) => v - bounds.min[k])) : 1;
    if (parent) {
      if (tile.geometricError > parent.tile.geometricError) problems.push(`${where}: geometricError grows from its parent`);
      if (bounds && parent.bounds && !inside(bounds, parent.bounds, 1e-9 * size)) problems.push(`${where}: box not inside its parent's box`);
    }
    if (tile.content) {
      ++contents;
      const uri = tile.content.uri;
      const contentFile = path.resolve(dir, decodeURIComponent(uri || ''));
      if (!uri || path.isAbsolute(uri) || !fs.existsSync(contentFile)) {
        problems.push(`${where}: content ${uri} missing`);
      } else {
        const v = await validateFile(contentFile);
        validation.push(v);
        const d = await checkDracoGltf(contentFile);
        if (d.primitives.length) draco.push(d);
        for (const p of d.problems) problems.push(`${where}: ${p}`);
        const { json } = readGltf(contentFile);
        for (const nodeIndex of json.scenes[json.scene || 0].nodes) {
          const node = json.nodes[nodeIndex];
          if (node.rotation || node.scale || node.matrix || node.children) {
            problems.push(`${where}: node ${nodeIndex} has a transform the checker does not handle`);
            continue;
          }
          const t = node.translation || [0, 0, 0];
          for (const prim of json.meshes[node.mesh].primitives) {
            const a = json.accessors[prim.attributes.POSITION];
            // y-up glTF -> z-up tileset frame: (x, y, z) -> (x, -z, y).
            const lo = a.min.map((v, k) => v + t[k]);
            const hi = a.max.map((v, k) => v + t[k]);
            const content = { min: [lo[0], -hi[2], lo[1]], max: [hi[0], -lo[2], hi[1]] };
            // Boxes are padded by a float step (QA round 57): no slack beyond double rounding.
            if (bounds && !inside(content, bounds, 1e-12 * size))
              problems.push(`${where}: content ${uri} ${JSON.stringify(content)} outside its box ${JSON.stringify(bounds)}`);
          }
        }
      }
    }
    for (const [i, child] of (tile.children || []).entries())
      await walk(child, `${where}.children[${i}]`, { tile, bounds });
  };
  await walk(root, 'root', null);
  return { dir, tiles, contents, problems, validation, draco };
}

const results = [];
for (const dir of process.argv.slice(2)) {
  try {
    results.push(await checkTileset(dir));
  } catch (e) {
    results.push({ dir, problems: [String(e)] });
  }
}
process.stdout.write(JSON.stringify(results) + '\n');
