// Validates glTF/GLB files with the Khronos validator; prints the report summary, exits 1 on errors.
const fs = require('fs');
const validator = require('gltf-validator');
(async () => {
  let failed = false;
  for (const f of process.argv.slice(2)) {
    const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(f)));
    const i = report.issues;
    console.log(`${f}: ${i.numErrors} errors, ${i.numWarnings} warnings, ${i.numInfos} infos`);
    for (const m of i.messages.filter(m => m.severity <= 1).slice(0, 20)) console.log(`  [${m.severity}] ${m.code} ${m.pointer || ''}: ${m.message}`);
    if (i.numErrors > 0) failed = true;
  }
  process.exit(failed ? 1 : 0);
})().catch(e => { console.error(e); process.exit(2); });
