// The side panel: timeline (play, pause, step, scrub), weather-timeline editor, parameter
// panel (every numeric and boolean field of the scenario's `parameters`, Table 2 of
// Cordonnier et al. 2018), undo/redo, save/load/export, and cancel for the running job or live
// event.
const $ = (id) => document.getElementById(id);
const WEATHER = ['from_day', 'sea_level_temperature_c', 'wind_from_deg', 'wind_speed_m_s', 'rain_snow_altitude_m', 'snowfall_per_week'];

export function setupPanels(app, send) {
  let playing = false;
  let waiting = false;
  let weather = [];
  let paramsShownFor = null;

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
  $('save').onclick = () => send({ type: 'save', name: $('name').value });
  $('load').onclick = () => send({ type: 'load', name: $('name').value });
  $('export').onclick = () => send({ type: 'export', name: $('name').value });

  function renderWeather() {
    const body = $('weather').querySelector('tbody');
    body.innerHTML = '';
    weather.forEach((w, i) => {
      const tr = document.createElement('tr');
      for (const k of WEATHER) {
        const td = document.createElement('td');
        const inp = document.createElement('input');
        inp.type = 'number'; inp.value = w[k]; inp.step = 'any';
        inp.onchange = () => { w[k] = Number(inp.value); };
        td.appendChild(inp); tr.appendChild(td);
      }
      const del = document.createElement('button');
      del.textContent = '×'; del.onclick = () => { weather.splice(i, 1); renderWeather(); };
      tr.appendChild(del);
      body.appendChild(tr);
    });
  }
  $('weather-add').onclick = () => {
    const last = weather[weather.length - 1] || { from_day: 0, sea_level_temperature_c: 5, wind_from_deg: 300, wind_speed_m_s: 8, rain_snow_altitude_m: 1000, snowfall_per_week: 1 };
    weather.push({ ...last, from_day: last.from_day + 10 });
    renderWeather();
  };
  $('weather-apply').onclick = () => {
    const sc = structuredClone(app.state.scenario);
    sc.weather = weather.map((w) => ({ ...w }));
    send({ type: 'set_scenario', scenario: sc });
  };

  // Parameter form: one input per number or boolean of scenario.parameters.
  function renderParams(params) {
    const root = $('params');
    root.innerHTML = '';
    const walk = (obj, path, parent) => {
      for (const [k, v] of Object.entries(obj)) {
        const p = [...path, k];
        if (v && typeof v === 'object' && !Array.isArray(v)) {
          const fs = document.createElement('fieldset');
          const lg = document.createElement('legend'); lg.textContent = k; fs.appendChild(lg);
          walk(v, p, fs); parent.appendChild(fs);
        } else if (typeof v === 'number' || typeof v === 'boolean') {
          const lab = document.createElement('label');
          const inp = document.createElement('input');
          inp.dataset.path = p.join('.');
          if (typeof v === 'boolean') { inp.type = 'checkbox'; inp.checked = v; } else { inp.type = 'number'; inp.step = 'any'; inp.value = v; }
          lab.append(`${k} `, inp); parent.appendChild(lab);
        }
      }
    };
    walk(params, [], root);
  }
  $('params-apply').onclick = () => {
    const sc = structuredClone(app.state.scenario);
    for (const inp of $('params').querySelectorAll('input')) {
      const path = inp.dataset.path.split('.');
      let o = sc.parameters;
      for (const k of path.slice(0, -1)) o = o[k];
      o[path[path.length - 1]] = inp.type === 'checkbox' ? inp.checked : Number(inp.value);
    }
    send({ type: 'set_scenario', scenario: sc });
  };

  return {
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
      for (const f of files) {
        const li = document.createElement('li');
        const a = document.createElement('a');
        a.href = `/files/${f}`; a.textContent = f.split('/').pop(); a.download = '';
        li.appendChild(a); ul.appendChild(li);
      }
    },
  };
}
