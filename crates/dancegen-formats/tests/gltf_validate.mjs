// Validates one .glb with the Khronos glTF-Validator (npm package `gltf-validator`) and prints
// the validation report as JSON on stdout.
//
// Usage: node gltf_validate.mjs <dir with node_modules/gltf-validator> <file.glb>
import { createRequire } from "node:module";
import { readFileSync } from "node:fs";
import { join, resolve } from "node:path";

const [, , prefix, file] = process.argv;
if (!prefix || !file) {
  console.error("usage: node gltf_validate.mjs <npm prefix> <file.glb>");
  process.exit(2);
}
const require = createRequire(join(resolve(prefix), "package.json"));
const validator = require("gltf-validator");
const bytes = new Uint8Array(readFileSync(file));
const report = await validator.validateBytes(bytes, {
  uri: file,
  maxIssues: 1000,
  externalResourceFunction: (uri) =>
    Promise.reject(new Error(`unexpected external resource ${uri}`)),
});
process.stdout.write(JSON.stringify(report));
