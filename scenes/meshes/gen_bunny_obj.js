#!/usr/bin/env node
// Converts the Stanford bunny of the npm package `bunny` (1.0.1, public domain; exports
// `positions` and `cells`) to scenes/meshes/bunny.obj.
//
//   cd /tmp && npm pack bunny && mkdir -p bunny && tar xzf bunny-1.0.1.tgz -C bunny
//   node scenes/meshes/gen_bunny_obj.js /tmp/bunny/package scenes/meshes/bunny.obj
//
// Steps: (1) copy vertices and triangles unchanged (coordinates in the package's units);
// (2) check closedness (every undirected edge in exactly two triangles, opposite directions);
// (3) fill every boundary loop by a fan of triangles from the loop's first vertex, oriented
// against the loop's existing neighbours (the 1.0.1 package is already closed: 0 loops);
// (4) orient outward (positive signed volume) by flipping all triangles if needed.
// No third-party code is used or committed; only the derived OBJ is.
'use strict';
const fs = require('fs');
const path = require('path');
const [pkgDir, out] = process.argv.slice(2);
if (!pkgDir || !out) {
  console.error('usage: gen_bunny_obj.js <unpacked bunny package dir> <out.obj>');
  process.exit(2);
}
const bunny = require(path.resolve(pkgDir, 'index.js'));
const V = bunny.positions.map((p) => p.slice(0, 3));
let F = bunny.cells.map((c) => c.slice(0, 3));

function directedEdges(F) {
  const D = new Map();
  for (const t of F) for (let i = 0; i < 3; i++) {
    const k = t[i] + ',' + t[(i + 1) % 3];
    D.set(k, (D.get(k) || 0) + 1);
  }
  return D;
}
// Boundary edges: directed edges a->b without a matching b->a. Holes are filled with the
// reversed orientation (b->a) so that the filled mesh stays consistently oriented.
const D = directedEdges(F);
const next = new Map();
for (const k of D.keys()) {
  const [a, b] = k.split(',').map(Number);
  if (!D.has(b + ',' + a)) next.set(b, a); // walk the hole as b -> a
}
let loops = 0, added = 0;
while (next.size > 0) {
  const start = next.keys().next().value;
  const loop = [start];
  let v = next.get(start);
  next.delete(start);
  while (v !== start) {
    if (!next.has(v)) throw new Error('boundary is not a set of simple loops at vertex ' + v);
    loop.push(v);
    const w = next.get(v);
    next.delete(v);
    v = w;
  }
  for (let i = 1; i + 1 < loop.length; i++) { F.push([loop[0], loop[i], loop[i + 1]]); added++; }
  loops++;
}
// Closedness check.
const D2 = directedEdges(F);
for (const [k, n] of D2) {
  const [a, b] = k.split(',');
  if (n !== 1 || D2.get(b + ',' + a) !== 1) throw new Error('not closed at edge ' + k);
}
// Outward orientation: positive signed volume.
let vol = 0;
for (const [a, b, c] of F) {
  const [p, q, r] = [V[a], V[b], V[c]];
  vol += (p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) + p[2] * (q[0] * r[1] - q[1] * r[0])) / 6;
}
if (vol < 0) { F = F.map(([a, b, c]) => [a, c, b]); vol = -vol; }
const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
for (const p of V) for (let a = 0; a < 3; a++) { lo[a] = Math.min(lo[a], p[a]); hi[a] = Math.max(hi[a], p[a]); }
const lines = [
  '# Stanford bunny (Stanford 3D Scanning Repository), from the npm package bunny@1.0.1',
  '# (public domain), converted by gen_bunny_obj.js. Units: as in the package (unitless).',
  `# ${V.length} vertices, ${F.length} triangles, closed; ${loops} boundary loops filled with ${added} triangles.`,
  `# bounds min ${lo.join(' ')} max ${hi.join(' ')}; volume ${vol.toFixed(4)}`,
];
for (const p of V) lines.push('v ' + p.join(' '));
for (const t of F) lines.push('f ' + t.map((i) => i + 1).join(' '));
fs.writeFileSync(out, lines.join('\n') + '\n');
console.log(lines.slice(2, 4).join('\n'));
