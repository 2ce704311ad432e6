// The side panel: timeline (play, pause, step, scrub), weather-timeline editor, parameter
// panel (every field of the scenario's `parameters`, grouped by phenomenon, each with the help,
// range and choices the server generates from the Rust parameter types: GET /api/parameters),
// undo/redo, save/load/export, and cancel for the running job or live event.
const $ = (id) => document.getElementById(id);

export function setupPanels(app, send) {
  let playing = false;
  let waiting = false;
  let weather = [];
  // The weather period's fields (name, label, unit, optional) and the period "add" starts from
  // in an empty table: the server's (GET /api/protocol), set by setProtocol.
  let weatherFields = [];
  let weatherDefault = null;
  let paramsShownFor = null;
  // path -> { help, doc, kind, min, max, choices } from the server (empty until it answers).
  let catalogue = new Map();
  fetch('/api/parameters').then((r) => (r.ok ? r.json() : [])).then((list) => {
    catalogue = new Map(list.map((p) => [p.path, p]));
    paramsShownFor = null;
    if (app.state) { paramsShownFor = JSON.stringify(app.state.scenario); renderParams(app.state.scenario.parameters); }
  }).catch(() => {});

  $('undo').onclick = () => send({ type: 'undo' });
  $('redo').onclick = () => send({ type: 'redo' });
  $('view-home').onclick = () => window.snowscape.setView('home');
  $('view-top').onclick = () => window.snowscape.setView('top');
  $('step').onclick = () => send({ type: 'step', days: 1 });
  $('cancel').onclick = () => { if (playing) $('play').click(); send({ type: 'cancel' }); };
  $('play').onclick = () => {
    playing = !playing;
    $('play').textContent = playing ? 'pause' : 'play';
    if (playing && !waiting) { waiting = true; send({ type: 'step', days: 1 }); }
  };
  $('scrub').oninput = () => send({ type: 'seek', index: Number($('scrub').value) });
  // The saved projects (GET /api/projects): offered in the name field, and a save over one of
  // them asks first.
  let projects = [];
  const refreshProjects = () => fetch('/api/projects').then((r) => (r.ok ? r.json() : [])).then((list) => {
    projects = list;
    const dl = $('projects');
    dl.innerHTML = '';
    for (const p of list) {
      const o = document.createElement('option');
      o.value = p.name;
      o.label = p.day === null ? p.name : `${p.name} (day ${p.day.toFixed(1)})`;
      dl.appendChild(o);
    }
    return list;
  }).catch(() => projects);
  refreshProjects();
  $('name').addEventListener('focus', refreshProjects);
  app.refreshProjects = refreshProjects;
  $('save').onclick = async () => {
    const name = $('name').value;
    const list = await refreshProjects();
    if (list.some((p) => p.name === name) && !window.confirm(`Project ${name} exists: overwrite it?`)) return;
    send({ type: 'save', name });
  };
  $('load').onclick = () => send({ type: 'load', name: $('name').value });
  $('export').onclick = () => send({ type: 'export', name: $('name').value });

  function renderWeather() {
    const body = $('weather').querySelector('tbody');
    body.innerHTML = '';
    weather.forEach((w, i) => {
      const tr = document.createElement('tr');
      for (const f of weatherFields) {
        const k = f.name;
        const td = document.createElement('td');
        const inp = document.createElement('input');
        inp.type = 'number'; inp.value = w[k] ?? ''; inp.step = 'any';
        if (f.optional) inp.placeholder = 'default';
        // An optional field left empty takes the scenario's default.
        inp.onchange = () => { w[k] = f.optional && inp.value === '' ? null : Number(inp.value); };
        td.appendChild(inp); tr.appendChild(td);
      }
      const del = document.createElement('button');
      del.textContent = '×'; del.onclick = () => { weather.splice(i, 1); renderWeather(); };
      tr.appendChild(del);
      body.appendChild(tr);
    });
  }
  $('weather-add').onclick = () => {
    const last = weather[weather.length - 1] || weatherDefault;
    if (!last) return;
    weather.push({ ...last, from_day: last.from_day + 10 });
    renderWeather();
  };
  $('weather-apply').onclick = () => {
    if (!window.confirm('Apply the weather timeline and restart the season from day 0?')) return;
    const sc = structuredClone(app.state.scenario);
    sc.weather = weather.map((w) => ({ ...w }));
    send({ type: 'set_scenario', scenario: sc });
  };

  // A bound as shown: the closest double to an open bound at 0 (e.g. 5e-324 for "> 0") is 0.
  const shown = (v) => (v === null || v === undefined ? null : Math.abs(v) < 1e-300 ? 0 : Number(v.toPrecision(6)));
  const open = (v) => v !== null && v !== 0 && Math.abs(v) < 1e-300;
  const rangeText = (info) => {
    const lo = info.min === null ? '(−∞' : `${open(info.min) ? '(' : '['}${shown(info.min)}`;
    const hi = info.max === null ? '∞)' : `${shown(info.max)}${open(info.max) ? ')' : ']'}`;
    return `${lo}, ${hi}`;
  };

  // Parameter form: one input per number, boolean or choice of scenario.parameters, each
  // phenomenon a collapsible section.
  function renderParams(params) {
    const root = $('params');
    root.innerHTML = '';
    const field = (k, v, p) => {
      const path = p.join('.');
      const info = catalogue.get(path);
      const lab = document.createElement('label');
      lab.className = 'param';
      let inp;
      if (info && info.kind === 'choice' && info.choices.length) {
        inp = document.createElement('select');
        for (const c of info.choices) {
          const o = document.createElement('option'); o.value = c; o.textContent = c; inp.appendChild(o);
        }
        inp.value = v;
      } else if (typeof v === 'boolean') {
        inp = document.createElement('input'); inp.type = 'checkbox'; inp.checked = v;
      } else if (typeof v === 'number') {
        inp = document.createElement('input'); inp.type = 'number'; inp.step = info && info.kind === 'integer' ? '1' : 'any'; inp.value = v;
        if (info && shown(info.min) !== null) inp.min = String(info.min);
        if (info && shown(info.max) !== null) inp.max = String(info.max);
      } else {
        return null;
      }
      inp.dataset.path = path;
      lab.append(`${k} `, inp);
      if (info) {
        lab.title = info.doc;
        const help = document.createElement('span');
        help.className = 'help';
        help.textContent = info.kind === 'number' || info.kind === 'integer' ? `${info.help} ${rangeText(info)}` : info.help;
        lab.appendChild(help);
      }
      return lab;
    };
    const walk = (obj, path, parent) => {
      for (const [k, v] of Object.entries(obj)) {
        const p = [...path, k];
        if (v && typeof v === 'object' && !Array.isArray(v)) {
          let box;
          if (path.length === 0) {
            box = document.createElement('details');
            box.className = 'section';
            const sm = document.createElement('summary'); sm.textContent = k; box.appendChild(sm);
          } else {
            box = document.createElement('fieldset');
            const lg = document.createElement('legend'); lg.textContent = k; box.appendChild(lg);
          }
          walk(v, p, box); parent.appendChild(box);
        } else {
          const lab = field(k, v, p);
          if (lab) parent.appendChild(lab);
        }
      }
    };
    walk(params, [], root);
  }
  $('params-apply').onclick = () => {
    if (!window.confirm('Apply the parameters and restart the season from day 0?')) return;
    const sc = structuredClone(app.state.scenario);
    for (const inp of $('params').querySelectorAll('input, select')) {
      const path = inp.dataset.path.split('.');
      let o = sc.parameters;
      for (const k of path.slice(0, -1)) o = o[k];
      const last = path[path.length - 1];
      if (inp.tagName === 'SELECT') o[last] = inp.value;
      else o[last] = inp.type === 'checkbox' ? inp.checked : Number(inp.value);
    }
    send({ type: 'set_scenario', scenario: sc });
  };

  return {
    // The server's protocol description: the weather table's columns.
    setProtocol(p) {
      weatherFields = p.weather_fields;
      weatherDefault = p.weather_default;
      const head = $('weather-head');
      head.innerHTML = '';
      for (const f of weatherFields) {
        const th = document.createElement('th');
        th.append(f.label, document.createElement('br'), f.unit);
        th.title = f.name + (f.optional ? ' (optional: empty takes the scenario default)' : '');
        head.appendChild(th);
      }
      head.appendChild(document.createElement('th'));
      renderWeather();
    },
    onState(s) {
      $('cancel').disabled = !s.busy;
      $('scrub').max = String(Math.max(0, s.snapshots.length - 1));
      $('scrub').value = String(s.current);
      $('day').textContent = `day ${s.day.toFixed(2)} of ${s.season_days} · ${s.snapshots.length} snapshots (${(s.snapshot_bytes / 2 ** 20).toFixed(0)} of ${(s.snapshot_budget_bytes / 2 ** 20).toFixed(0)} MiB) · undo ${s.undo} / redo ${s.redo} · ${s.season_avalanches} season avalanches · snow ${(s.snow_volume_m3 / 1e6).toFixed(3)} hm³`;
      const key = JSON.stringify(s.scenario);
      if (key !== paramsShownFor) {
        paramsShownFor = key;
        weather = s.weather.map((w) => ({ ...w }));
        renderWeather();
        renderParams(s.scenario.parameters);
      }
      if (waiting && !s.busy) {
        waiting = false;
        if (playing && s.day < s.season_days) { waiting = true; setTimeout(() => send({ type: 'step', days: 1 }), 50); }
        else if (playing) { playing = false; $('play').textContent = 'play'; }
      }
    },
    showFiles(files) {
      const ul = $('files');
      ul.innerHTML = '';
      // The whole export as one zip (GET /api/export/<name>).
      const name = files.length ? files[0].split('/')[1] : null;
      if (name) {
        const li = document.createElement('li');
        const a = document.createElement('a');
        a.href = `/api/export/${encodeURIComponent(name)}`; a.textContent = `all (${name}.zip)`; a.download = `${name}.zip`; a.id = 'export-zip';
        li.appendChild(a); ul.appendChild(li);
      }
      for (const f of files) {
        const li = document.createElement('li');
        const a = document.createElement('a');
        a.href = `/files/${f}`; a.textContent = f.split('/').pop(); a.download = '';
        li.appendChild(a); ul.appendChild(li);
      }
    },
  };
}
