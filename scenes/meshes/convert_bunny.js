// Converts the npm package `bunny` (the Stanford bunny, public domain; positions and cells in its
// index.js) to Wavefront OBJ. Run: npm pack bunny && tar xzf bunny-*.tgz &&
//   node scenes/meshes/convert_bunny.js package/index.js > scenes/meshes/bunny.obj
const bunny = require(require('path').resolve(process.argv[2]));
const lines = [
  '# The Stanford bunny, from the npm package "bunny" 1.0.1 (public domain, Stanford 3D Scanning',
  '# Repository), converted by scenes/meshes/convert_bunny.js. Units as in the package.',
  `# ${bunny.positions.length} vertices, ${bunny.cells.length} triangles`,
];
for (const p of bunny.positions) lines.push(`v ${p[0]} ${p[1]} ${p[2]}`);
for (const c of bunny.cells) lines.push(`f ${c[0] + 1} ${c[1] + 1} ${c[2] + 1}`);
process.stdout.write(lines.join('\n') + '\n');
