// Shared helpers of the validation scripts the C++ tests run: real glTF / Draco clients
// (Khronos glTF-Validator, Google's draco3d decoder) applied to the files libmrtile writes.
import fs from 'node:fs';
import path from 'node:path';
import validator from 'gltf-validator';
import draco3d from 'draco3d';

// Reads a .glb or .gltf: returns { json, bin } with bin = the GLB BIN chunk or the decoded
// data URI of buffer 0 (libmrtile writes single-buffer assets).
export function readGltf(file) {
  const bytes = fs.readFileSync(file);
  if (bytes.length >= 12 && bytes.readUInt32LE(0) === 0x46546c67) {
    const jsonLength = bytes.readUInt32LE(12);
    const json = JSON.parse(bytes.subarray(20, 20 + jsonLength).toString('utf8'));
    let bin = null;
    const binStart = 20 + jsonLength;
    if (bytes.length > binStart + 8) {
      const binLength = bytes.readUInt32LE(binStart);
      bin = bytes.subarray(binStart + 8, binStart + 8 + binLength);
    }
    return { json, bin };
  }
  const json = JSON.parse(bytes.toString('utf8'));
  let bin = null;
  const uri = json.buffers && json.buffers[0] && json.buffers[0].uri;
  if (uri && uri.startsWith('data:')) bin = Buffer.from(uri.slice(uri.indexOf(',') + 1), 'base64');
  else if (uri) bin = fs.readFileSync(path.resolve(path.dirname(file), decodeURIComponent(uri)));
  return { json, bin };
}

// Runs the Khronos validator; returns counts per severity and the issues (code, message, pointer).
export async function validateFile(file) {
  const bytes = new Uint8Array(fs.readFileSync(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,
    writeTimestamp: false,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)), (err, data) =>
          err ? reject(err.toString()) : resolve(new Uint8Array(data)));
      }),
  });
  const issues = report.issues;
  return {
    file,
    errors: issues.numErrors,
    warnings: issues.numWarnings,
    infos: issues.numInfos,
    hints: issues.numHints,
    messages: issues.messages.map((m) => ({ code: m.code, severity: m.severity, message: m.message, pointer: m.pointer })),
  };
}

let decoderModule = null;
export async function dracoDecoder() {
  if (!decoderModule) decoderModule = await draco3d.createDecoderModule({});
  return decoderModule;
}

// Decodes one Draco buffer: counts, bounds of POSITION, and per-unique-id attribute info.
export async function decodeDraco(bytes) {
  const m = await dracoDecoder();
  const decoder = new m.Decoder();
  const buffer = new m.DecoderBuffer();
  buffer.Init(new Int8Array(bytes.buffer, bytes.byteOffset, bytes.byteLength), bytes.byteLength);
  const mesh = new m.Mesh();
  const status = decoder.DecodeBufferToMesh(buffer, mesh);
  const out = { ok: status.ok(), error: status.ok() ? null : status.error_msg() };
  if (status.ok()) {
    out.points = mesh.num_points();
    out.faces = mesh.num_faces();
    out.attributes = {};
    for (let i = 0; i < mesh.num_attributes(); ++i) {
      const a = decoder.GetAttribute(mesh, i);
      out.attributes[a.unique_id()] = { type: a.attribute_type(), components: a.num_components() };
    }
    const posId = decoder.GetAttributeId(mesh, m.POSITION);
    const pos = decoder.GetAttribute(mesh, posId);
    const values = new m.DracoFloat32Array();
    decoder.GetAttributeFloatForAllPoints(mesh, pos, values);
    const min = [Infinity, Infinity, Infinity];
    const max = [-Infinity, -Infinity, -Infinity];
    for (let i = 0; i < values.size(); ++i) {
      const v = values.GetValue(i);
      min[i % 3] = Math.min(min[i % 3], v);
      max[i % 3] = Math.max(max[i % 3], v);
    }
    out.min = min;
    out.max = max;
    m.destroy(values);
  }
  m.destroy(mesh);
  m.destroy(buffer);
  m.destroy(decoder);
  return out;
}

// Decodes every Draco primitive of a glTF asset and compares it with the accessors that describe it.
export async function checkDracoGltf(file) {
  const { json, bin } = readGltf(file);
  const primitives = [];
  const problems = [];
  const m = await dracoDecoder();
  const typeOf = { POSITION: m.POSITION, NORMAL: m.NORMAL, COLOR_0: m.COLOR };
  for (const [mi, mesh] of (json.meshes || []).entries()) {
    for (const [pi, prim] of mesh.primitives.entries()) {
      const ext = prim.extensions && prim.extensions.KHR_draco_mesh_compression;
      if (!ext) continue;
      const where = `meshes[${mi}].primitives[${pi}]`;
      const view = json.bufferViews[ext.bufferView];
      const bytes = bin.subarray(view.byteOffset || 0, (view.byteOffset || 0) + view.byteLength);
      const d = await decodeDraco(bytes);
      if (!d.ok) { problems.push(`${where}: draco decode failed: ${d.error}`); continue; }
      const position = json.accessors[prim.attributes.POSITION];
      if (d.points !== position.count) problems.push(`${where}: decoded ${d.points} points, accessor count ${position.count}`);
      if (prim.indices !== undefined && d.faces * 3 !== json.accessors[prim.indices].count)
        problems.push(`${where}: decoded ${d.faces} faces, indices count ${json.accessors[prim.indices].count}`);
      for (const [name, id] of Object.entries(ext.attributes)) {
        const a = d.attributes[id];
        if (!a) { problems.push(`${where}: attribute ${name} id ${id} not in the Draco data`); continue; }
        if (typeOf[name] !== undefined && a.type !== typeOf[name]) problems.push(`${where}: ${name} id ${id} has Draco type ${a.type}`);
        if (json.accessors[prim.attributes[name]].count !== d.points) problems.push(`${where}: ${name} count differs from decoded points`);
      }
      for (let k = 0; k < 3; ++k) {
        if (Math.fround(position.min[k]) !== d.min[k] || Math.fround(position.max[k]) !== d.max[k])
          problems.push(`${where}: POSITION min/max ${JSON.stringify([position.min, position.max])} != decoded ${JSON.stringify([d.min, d.max])}`);
      }
      primitives.push({ mesh: mi, primitive: pi, points: d.points, faces: d.faces, min: d.min, max: d.max, bytes: view.byteLength });
    }
  }
  return { file, primitives, problems };
}
