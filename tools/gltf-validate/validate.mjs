#!/usr/bin/env node
// Validates glTF 2.0 files (.gltf or .glb) with the Khronos glTF validator.
//
// Usage: node validate.mjs FILE...
// Prints one line per file with its error, warning, info and hint counts (and each error or
// warning message), and exits with status 1 when any file has errors (2 on bad usage).
import { readFile } from 'node:fs/promises';
import path from 'node:path';
import validator from 'gltf-validator';

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error('usage: node validate.mjs FILE...');
  process.exit(2);
}

let failed = false;
for (const file of files) {
  let report;
  try {
    const bytes = new Uint8Array(await readFile(file));
    report = await validator.validateBytes(bytes, {
      uri: path.basename(file),
      maxIssues: 0,
      // Resources of a .gltf (external .bin files) resolve beside it; data URIs need nothing.
      externalResourceFunction: (uri) =>
        readFile(path.join(path.dirname(file), decodeURIComponent(uri))).then((b) => new Uint8Array(b)),
    });
  } catch (err) {
    console.log(`${file}: could not be validated: ${err.message ?? err}`);
    failed = true;
    continue;
  }
  const issues = report.issues;
  console.log(
    `${file}: ${issues.numErrors} errors, ${issues.numWarnings} warnings, ` +
      `${issues.numInfos} infos, ${issues.numHints} hints`,
  );
  for (const m of issues.messages) {
    if (m.severity <= 1) {
      const kind = m.severity === 0 ? 'error' : 'warning';
      console.log(`  ${kind} ${m.code} at ${m.pointer ?? m.offset ?? '?'}: ${m.message}`);
    }
  }
  if (issues.numErrors > 0) failed = true;
}
process.exit(failed ? 1 : 0);
