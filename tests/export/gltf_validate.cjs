// Runs the Khronos glTF validator (npm gltf-validator) on a .glb and prints its report's
// summary and messages as JSON on stdout; exits 1 when the report has errors, 2 on a failure.
//   node gltf_validate.cjs <node_modules folder> <file.glb>
const fs = require('fs');
const path = require('path');
const [modules, file] = process.argv.slice(2);
const validator = require(path.join(modules, 'gltf-validator'));
validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {uri: path.basename(file), maxIssues: 100})
  .then((report) => {
    const issues = report.issues;
    console.log(JSON.stringify({
      errors: issues.numErrors, warnings: issues.numWarnings, infos: issues.numInfos,
      messages: issues.messages.map((m) => `${m.severity} ${m.code} ${m.pointer || ''}: ${m.message}`),
      info: report.info,
    }, null, 1));
    process.exit(issues.numErrors > 0 ? 1 : 0);
  })
  .catch((error) => { console.error(String(error)); process.exit(2); });
