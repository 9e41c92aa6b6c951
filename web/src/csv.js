// CSV text (as ifab writes it: a header line, comma-separated, "quoted" text fields) to columns.
export function parseCsv(text) {
  const lines = text.split('\n').filter((l) => l.length > 0);
  if (lines.length === 0) return { header: [], rows: 0, col: {} };
  const split = (line) => {
    const out = [];
    let cur = '', quoted = false;
    for (let i = 0; i < line.length; i++) {
      const c = line[i];
      if (quoted) {
        if (c === '"' && line[i + 1] === '"') { cur += '"'; i++; }
        else if (c === '"') quoted = false;
        else cur += c;
      } else if (c === '"') quoted = true;
      else if (c === ',') { out.push(cur); cur = ''; }
      else cur += c;
    }
    out.push(cur);
    return out;
  };
  const header = split(lines[0]);
  const col = {};
  header.forEach((h) => { col[h] = []; });
  for (let r = 1; r < lines.length; r++) {
    const cells = split(lines[r]);
    header.forEach((h, i) => {
      const v = cells[i];
      const x = Number(v);
      col[h].push(v !== '' && v !== undefined && Number.isFinite(x) ? x : v);
    });
  }
  return { header, rows: lines.length - 1, col };
}

// Mean, population std, min and max of numbers.
export function stats(values) {
  const v = values.filter((x) => typeof x === 'number' && Number.isFinite(x));
  if (v.length === 0) return { n: 0, mean: NaN, std: NaN, min: NaN, max: NaN };
  const mean = v.reduce((a, b) => a + b, 0) / v.length;
  const sd = v.length > 1 ? Math.sqrt(v.reduce((a, b) => a + (b - mean) ** 2, 0) / (v.length - 1)) : 0;
  return { n: v.length, mean, std: sd, min: Math.min(...v), max: Math.max(...v) };
}
