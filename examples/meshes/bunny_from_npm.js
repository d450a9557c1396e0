// bunny_from_npm.js - writes bunny.obj from the npm package `bunny` 1.0.1 (public domain).
// Usage: cd /tmp && npm pack bunny && tar xzf bunny-1.0.1.tgz &&
//        node bunny_from_npm.js /tmp/package/index.js > bunny.obj
const b = require(require("path").resolve(process.argv[2]));
const out = ["# Stanford bunny (Stanford 3D Scanning Repository) via the npm package bunny 1.0.1, public domain"];
for (const p of b.positions) out.push("v " + p.join(" "));
for (const c of b.cells) out.push("f " + c.map((i) => i + 1).join(" "));
process.stdout.write(out.join("\n") + "\n");
