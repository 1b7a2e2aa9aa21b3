#!/usr/bin/env node
// Runs the Khronos glTF-Validator (npm package `gltf-validator`, a library: `npm install -g
// gltf-validator`, then run with NODE_PATH="$(npm root -g)") on each .glb/.gltf given.
// Prints one summary line per file and every error, warning and info; exits 1 if any file has an
// error (or cannot be read), 2 if the validator is not installed.
'use strict';
const fs = require('fs');
const path = require('path');
let validator;
try {
  validator = require('gltf-validator');
} catch (e) {
  console.error('gltf-validator is not installed (npm install -g gltf-validator; NODE_PATH="$(npm root -g)")');
  process.exit(2);
}
(async () => {
  let failed = false;
  for (const file of process.argv.slice(2)) {
    try {
      const bytes = new Uint8Array(fs.readFileSync(file));
      const report = await validator.validateBytes(bytes, {
        uri: path.basename(file),
        maxIssues: 100,
        externalResourceFunction: (uri) =>
          new Promise((resolve, reject) => {
            fs.readFile(path.resolve(path.dirname(file), decodeURIComponent(uri)), (err, data) =>
              err ? reject(err.toString()) : resolve(new Uint8Array(data)));
          }),
      });
      const i = report.issues;
      console.log(`${file}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos, ${i.numHints} hints (gltf-validator ${report.validatorVersion})`);
      for (const m of i.messages) {
        if (m.severity <= 2) {
          console.log(`  ${['error', 'warning', 'info'][m.severity]} ${m.code} at ${m.pointer || ''}: ${m.message}`);
        }
      }
      if (i.numErrors > 0) failed = true;
    } catch (e) {
      console.log(`${file}: cannot validate: ${e}`);
      failed = true;
    }
  }
  process.exit(failed ? 1 : 0);
})();
