// Usage: node validate.mjs FILE... -> JSON array, one Khronos glTF-Validator summary per file.
import { validateFile } from './lib.mjs';

const results = [];
for (const file of process.argv.slice(2)) {
  try {
    results.push(await validateFile(file));
  } catch (e) {
    results.push({ file, errors: 1, warnings: 0, infos: 0, hints: 0, messages: [{ code: 'LOAD_FAILED', message: String(e) }] });
  }
}
process.stdout.write(JSON.stringify(results) + '\n');
