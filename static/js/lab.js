// GyroLab session page: charts, the position stepper, and the three ways of recording
// (typed grid, CSV file, simulated gyro over a WebSocket).  No inline scripts: the page's
// data arrive as JSON in <script type="application/json"> blocks.
(() => {
  "use strict";
  const config = JSON.parse(document.getElementById("lab-config").textContent);
  const figures = JSON.parse(document.getElementById("lab-figures").textContent);
  // A message in the page's language; a plural one arrives as {one, other}, chosen by n.
  const t = (key, params = {}) => {
    let text = config.messages[key] || key;
    if (typeof text === "object") text = Number(params.n) === 1 ? text.one : text.other;
    // a value quoted from a cell, without bidirectional controls that would reorder the rest
    return text.replace(/\{(\w+)\}/g, (_, name) => String(params[name] ?? "").replace(/[\u202a-\u202e\u2066-\u2069]/g, ""));
  };
  const base = `/lab/sessions/${config.sessionId}`;
  const MAX_FILE_BYTES = 5_000_000;
  const LIVE_WINDOW = 600;
  const selected = { heading: 1, latitude: 1 };

  // --- charts -----------------------------------------------------------------------------
  GyroCharts.showAll(figures);

  async function postJson(path, body) {
    return postBody(path, "application/json", JSON.stringify(body));
  }
  // A file's bytes as they are (an Excel workbook, which the server reads).
  async function postBytes(path, buffer) {
    return postBody(path, "application/octet-stream", buffer);
  }
  async function postBody(path, type, body) {
    const response = await fetch(base + path, {
      method: "POST",
      headers: { "Content-Type": type, Accept: "application/json", "X-CSRF-Token": config.csrf },
      body,
    });
    let payload = {};
    try { payload = await response.json(); } catch (error) { payload = {}; }
    if (!response.ok) {
      let detail = typeof payload.detail === "string" ? payload.detail : t("js.failed");
      if (Array.isArray(payload.detail) && payload.detail.length) {  // a 422: its first field
        const first = payload.detail[0];
        const loc = Array.isArray(first.loc) ? first.loc : [];
        const at = loc.indexOf("columns");  // a position's readings: say which position
        detail = at >= 0 && at + 1 < loc.length
          ? t("js.position_problem", { position: loc[at + 1], problem: first.msg })
          : String(first.msg || detail);
      }
      throw new Error(detail);
    }
    return payload;
  }

  // After a save the page reloads with the new result.  The control that was used keeps
  // the keyboard focus, and a status line announces what happened and the new result.
  const announceKey = `gyrolab-lab-announce-${config.sessionId}`;
  function reloadSoon(message = t("js.saved")) {
    const active = document.activeElement;
    const part = active?.closest("[data-part]")?.dataset.part || active?.closest(".part")?.dataset.part;
    const className = active && active !== document.body ? [...active.classList][0] : null;
    sessionStorage.setItem(announceKey, JSON.stringify({ message, part, className }));
    setTimeout(() => window.location.reload(), 400);
  }
  function announceAfterReload() {
    const saved = JSON.parse(sessionStorage.getItem(announceKey) || "null");
    sessionStorage.removeItem(announceKey);
    if (!saved) return;
    const section = saved.part ? document.getElementById(`part-${saved.part}`) : null;
    const summary = section?.querySelector(".summary")?.innerText.replace(/\s+/g, " ").trim() || "";
    const target = section && saved.className ? section.querySelector(`.${CSS.escape(saved.className)}:not([hidden])`) : null;
    if (target && target.offsetParent !== null) target.focus();
    // written a moment after load, so screen readers notice the live region change
    setTimeout(() => { document.getElementById("lab-announcer").textContent = `${saved.message} ${summary}`.trim(); }, 300);
  }

  // --- stepper and method tabs ------------------------------------------------------------
  function selectPosition(part, position) {
    selected[part] = position;
    const section = document.getElementById(`part-${part}`);
    section.querySelectorAll(".step").forEach((step) => {
      step.setAttribute("aria-selected", String(Number(step.dataset.position) === position));
    });
    section.querySelectorAll(".axis").forEach((axis) => {
      axis.classList.toggle(
        "selected",
        Number(axis.dataset.position) === position || Number(axis.dataset.return) === position,
      );
    });
    section.querySelectorAll(".readings-grid").forEach((grid) => markColumn(grid, position));
    updateTurnHint(part);
  }
  // The chosen position's column of the typed grid is marked and scrolled into view.
  function markColumn(grid, position) {
    grid.querySelectorAll("tr").forEach((row) => {
      [...row.children].forEach((cell, index) => cell.classList.toggle("column-selected", index === position));
    });
    const header = grid.querySelectorAll("thead th")[position];
    const wrap = grid.closest(".grid-wrap");
    if (header && wrap && wrap.scrollWidth > wrap.clientWidth) {
      wrap.scrollLeft = Math.max(0, header.offsetLeft - wrap.clientWidth / 3);
    }
  }

  // The chosen tab and position survive the reload that follows each save.
  const memoryKey = `gyrolab-lab-${config.sessionId}`;
  const memory = JSON.parse(sessionStorage.getItem(memoryKey) || "{}");
  function remember(part, values) {
    memory[part] = { ...(memory[part] || {}), ...values };
    sessionStorage.setItem(memoryKey, JSON.stringify(memory));
  }

  document.querySelectorAll(".step").forEach((step) => {
    step.addEventListener("click", () => {
      selectPosition(step.dataset.part, Number(step.dataset.position));
      remember(step.dataset.part, { position: Number(step.dataset.position) });
    });
  });
  function showMethod(part, method) {
    const section = document.getElementById(`part-${part}`);
    const tab = section.querySelector(`.method-tab[data-method="${method}"]`);
    if (!tab) return;
    section.querySelectorAll(".method-tab").forEach((other) => {
      other.classList.toggle("active", other === tab);
      other.setAttribute("aria-pressed", String(other === tab));
    });
    section.querySelectorAll(".method-panel").forEach((panel) => {
      panel.hidden = panel.dataset.method !== method;
    });
  }
  document.querySelectorAll(".method-tab").forEach((tab) => {
    tab.addEventListener("click", () => {
      showMethod(tab.dataset.part, tab.dataset.method);
      remember(tab.dataset.part, { method: tab.dataset.method });
    });
  });

  // --- typed grid -------------------------------------------------------------------------
  // A number as typed or pasted: "10.74", "-1e-3", or with a decimal comma "10,74"; typed
  // with a Chinese input method's full-width forms ("－３．２５"), its full stop between
  // digits ("10。74", the "." key in Chinese punctuation) or the minus sign "−" too.
  const plain = (text) =>
    text.normalize("NFKC").replace(/\u2212/g, "-").replace(/(\d)\u3002(?=\d)/g, "$1.");
  // A cell's number as written, a decimal comma as a point ("10,74" → "10.74").
  function numberText(text) {
    const value = plain(text).trim();
    return /^[-+]?\d*,\d+([eE][-+]?\d+)?$/.test(value) ? value.replace(",", ".") : value;
  }
  // a spreadsheet's error value, a formula that failed: app.core.column_names.SPREADSHEET_ERRORS
  const SPREADSHEET_ERROR = /^#(?:DIV\/0!|N\/A!?|VALUE!|REF!|NAME\?|NUM!|NULL!|SPILL!|CALC!|FIELD!|GETTING_DATA|BLOCKED!|CONNECT!|BUSY!|UNKNOWN!)$/i;
  function parseCell(text) {
    const value = numberText(text);
    if (value === "") return { empty: true };
    if (SPREADSHEET_ERROR.test(value.trim())) return { error: "js.spreadsheet_error", failed: true };
    if (!/^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(value)) return { error: "js.not_a_number" };
    const number = Number(value);
    if (!Number.isFinite(number)) return { error: "js.not_finite" };
    return { value: number };
  }

  // A block copied from a spreadsheet or a handout table → rows of cells.  Recognises a
  // header row (position_1, 位置1, sample, 序号 …) and a row-number column, which are
  // dropped and reported, never read as readings.
  const ROW_NUMBER_NAMES = new Set(["sample", "n", "#", "no", "no.", "index", "序号", "编号", "次数", "row", "i"]);
  // A row under the names that only names units, as app.core.readings.is_units_row reads it.
  const UNIT_NAME = /^(?:°|deg|rad|mrad|dph|dps|s|ms|h|hr|min|hz|°c|℃|c|k|v|mv|lsb|度|秒|小时|摄氏度)(?:\/(?:s|h|hr|min|秒|小时))?$/;
  // a rate unit, read or not ("mdeg/s", "°/min"), never a speed ("m/s"): app.core.column_names.RATE_LIKE
  const RATE_LIKE = /^(?:m|µ|μ|u|k)?(?:deg|degrees?|°|º|˚|rad|arcsec|arcmin|度|弧度|角秒)\/(?:s|sec|h|hr|min|秒|小时|时|分|分钟)$/;
  const UNITS_LABELS = new Set(["unit", "units", "单位"]);  // the row named in its first cell
  function isUnitsRow(cells) {
    let names = cells.map((cell) => plain(cell).replace(/[\s()[\]]/g, "").toLowerCase()).filter(Boolean);
    if (names.length && UNITS_LABELS.has(names[0].replace(/[:：]+$/, ""))) names = names.slice(1);
    return names.length > 0 && names.every((name) => UNIT_NAME.test(name) || RATE_LIKE.test(name)) &&
      names.some((name) => name.includes("/") || name === "dph" || name === "dps");
  }

  // How a header names a position, as app.core.table_headers reads it: "位置1", "P1", "第1位置",
  // the handout's "位置 | 1 | 2 | 3 | 4", or the turntable's angle ("90°").
  const NUMBER = "(\\d+|[一二三四五六七八九十])";
  const POSITION_NAMES = [
    new RegExp(`^(?:position|pos\\.?|p|位置)\\s*[_#.\\-]?\\s*${NUMBER}\\s*号?$`),
    new RegExp(`^第\\s*${NUMBER}\\s*个?\\s*位置$`),
    new RegExp(`^${NUMBER}\\s*号\\s*位置$`),
    new RegExp(`^(?:ω|omega)\\s*_?\\s*${NUMBER}$`),  // the handout's ω1 … ω4
  ];
  const ANGLE_NAME = /^[+-]?\d+(?:\.\d+)?\s*(?:°|º|˚|度|deg|degrees?)$/;
  const headerName = (cell) => plain(cell).trim().toLowerCase().replace(/\s*[(\[][^()\[\]]*[)\]]$/, "");
  function namesPosition(cell) {
    const name = headerName(cell);
    return /^\d+$/.test(name) || ANGLE_NAME.test(name) || POSITION_NAMES.some((pattern) => pattern.test(name));
  }
  // A first row of numbers that numbers the positions: 1, 2, 3, 4 or the angles 0, 90, 180, 270.
  function numbersThePositions(cells) {
    const values = cells.filter((cell) => cell !== "").map(Number);
    if (values.length < 3 || values.some((value) => !Number.isFinite(value))) return false;
    if (values.every((value, i) => value === i + 1)) return true;
    const step = 360 / values.length;
    return values[0] === 0 && values.every((value, i) => Math.abs(value - i * step) < 1e-9);
  }
  // The angles a header heads its position columns with ("0° | 90° | 180° | 270°", or
  // "0, 90, 180, 270" over rows), in column order; null where it counts them ("1, 2, 3, 4")
  // or names them -- app.core.table_headers.header_angles.
  function headerAngles(header) {
    const named = header.map(headerName).filter((name) => name !== "");
    const angles = named.filter((name) => ANGLE_NAME.test(name)).map((name) => parseFloat(name));
    if (angles.length >= 3) return angles;
    const numbers = named.filter((name) => /^[+-]?\d+(?:\.\d+)?$/.test(name));
    if (numbers.length < 3 || numbers.every((name, i) => name === String(i + 1))) return null;
    return numbersThePositions(numbers) ? numbers.map(Number) : null;
  }
  // Whether angles run round the other way from the session's (clockwise positive,
  // lab-reference §3) -- app.core.table_headers.turned_other_way.
  function turnedOtherWay(given, expected) {
    if (!given || given.length !== expected.length || given.length < 3) return false;
    const offsets = (angles, sign) => angles.map((angle) => ((sign * (angle - angles[0])) % 360 + 360) % 360);
    const same = (a, b) => a.every((value, i) => Math.abs(((value - b[i] + 540) % 360) - 180) < 1e-6);
    const ahead = offsets(given, 1);
    return same(ahead, offsets(expected, -1)) && !same(ahead, offsets(expected, 1));
  }
  const degrees = (angles) => angles.map((angle) => `${angle}°`).join(", ");
  // The rate unit a pasted header ("位置1 (°/s)", "rate [rad/s]") and its row of units
  // name, canonical ("deg/s"); null where they name none or several -- as
  // app.core.readings reads a file's, which the lab page then holds to the chosen unit.
  const RATE_UNITS = new Map(Object.entries(config.rateUnits));
  function namedRateUnit(header, units) {
    const named = new Set();
    let unread = null;  // a rate in a unit GyroLab does not read ("mdeg/s", "°/min")
    const take = (text) => {
      const key = plain(text).replace(/[\s·()[\]（）]/g, "").toLowerCase();
      const unit = RATE_UNITS.get(key);
      if (unit) named.add(unit);
      else if (RATE_LIKE.test(key)) unread = unread || text.trim();
    };
    (header || []).forEach((cell) => {
      const bracketed = plain(cell).trim().match(/[(\[（【]([^()\[\]（）【】]*)[)\]）】]$/);
      if (bracketed) take(bracketed[1]);
    });
    (units || []).forEach(take);
    return { unit: named.size === 1 ? [...named][0] : null, unread };
  }
  // A note as said: a message's key, or its key and values.
  const said = (note) => (Array.isArray(note) ? t(note[0], note[1]) : t(note));

  // A row of means or another summary ("平均值", "mean"): the handout ends its tables with one;
  // its labels are the server's, sent with the page.
  const SUMMARY_LABELS = new Set(config.summaryLabels);  // app.core.table_headers.SUMMARY_LABELS
  const isSummary = (row) => row.some((cell) => SUMMARY_LABELS.has(headerName(cell).replace(/[:：]$/, "").trim()));

  // A long table: one reading per row beside its position ("位置 | 读数", "position, rate",
  // "angle, reading (°/h)"), as app.core.long_headers names its columns (sent with the page).
  const LONG_ROLES = Object.entries(config.longRoles).flatMap(([role, names]) => names.map((name) => [name, role]));
  const ROLE_OF = new Map(LONG_ROLES);
  function longRole(cell) {
    let name = plain(cell).trim().toLowerCase().replace(/\s*[(\[（【][^()\[\]（）【】]*[)\]）】]$/, "");
    name = name.replace(/[\s_]+/g, " ").trim();
    const suffixed = name.match(/^(.+?) (?:deg h|deg s|dph|dps|rad s|deg|s|c)$/);
    if (suffixed && ROLE_OF.has(suffixed[1])) name = suffixed[1];
    return ROLE_OF.get(name);
  }
  function longColumns(header) {
    const found = {};
    header.forEach((cell, index) => {
      const role = longRole(cell);
      if (role) (found[role] = found[role] || []).push(index);
    });
    const one = (role) => (found[role] && found[role].length === 1 ? found[role][0] : undefined);
    const key = one("position") ?? one("angle_deg");
    const byAngle = one("position") === undefined;  // keyed by the turntable's angle
    return one("value") !== undefined && key !== undefined ? { key, value: one("value"), byAngle } : null;
  }
  // A long table's angle as a cell writes it, with or without its unit ("90", "90°", "90度").
  const angleOf = (label) => parseFloat(headerName(label).replace(/\s*(?:°|º|˚|度|deg|degrees?)$/, ""));
  // Each position's readings put in its column: "3", "P3", "位置3" is position 3; an angle
  // at the position of the session's whose dial angle it is (clockwise positive, as
  // app.lab.file_pages.file_positions saves a file's); labels counting from 0, other
  // angles or words: the positions in the order the rows give them.
  function longBlock(body, long, columns, part) {
    const labels = [];
    const readings = new Map();
    body.forEach((row) => {
      const label = (row[long.key] || "").trim();
      if (!readings.has(label)) { labels.push(label); readings.set(label, []); }
      readings.get(label).push(row[long.value] ?? "");
    });
    const numberOf = (label) => {
      const name = headerName(label);
      if (/^\d+$/.test(name)) return Number(name);
      const named = POSITION_NAMES.map((pattern) => name.match(pattern)).find(Boolean);
      return named && /^\d+$/.test(named[1]) ? Number(named[1]) : NaN;
    };
    const dial = (config.angles[part] || []).slice(0, columns);
    const atAngle = (label) => {
      const angle = angleOf(label);
      const k = dial.findIndex((at) => Math.abs(((angle - at) % 360 + 540) % 360 - 180) < 1e-6);
      return k + 1 || NaN;
    };
    let numbers = labels.map(long.byAngle ? atAngle : numberOf);
    const fromZero = numbers.includes(0) && numbers.every((n) => n < numbers.length) && new Set(numbers).size === numbers.length;
    if (fromZero) numbers = numbers.map((n) => n + 1);
    if (!numbers.every((n) => n >= 1 && n <= columns) || new Set(numbers).size !== numbers.length) {
      numbers = labels.map((_, i) => i + 1);
    }
    const length = Math.max(...labels.map((label) => readings.get(label).length));
    const width = Math.max(...numbers);
    const rows = Array.from({ length }, () => new Array(width).fill(undefined));
    labels.forEach((label, i) => {
      readings.get(label).forEach((value, r) => { rows[r][numbers[i] - 1] = value; });
    });
    return rows;
  }

  // Lines about the table above its header, as a whole sheet copied has them (a title, a
  // name and student number, the date): passed over up to the first row, within ten,
  // that names two positions or more, where no line above it holds two numbers --
  // app.core.readings reads a file so.
  // a cell of words (a name, a label), not a number nor a reading's failed formula ("#DIV/0!")
  const isText = (cell) => cell !== "" && Boolean(parseCell(cell).error) && !parseCell(cell).failed;
  // a header: two positions named ("位置1", "P2", "90°"), or numbered beside a label, as the
  // handout's "位置 | 1 | 2 | 3 | 4"
  const namesPositions = (row) => row.filter((cell) => isText(cell) && namesPosition(cell)).length >= 2 ||
    (row.some(isText) && numbersThePositions(row.filter((cell) => cell !== "" && !isText(cell))));
  function linesAbove(rows) {
    if (rows.length === 0 || namesPositions(rows[0])) return 0;
    for (let r = 1; r < Math.min(rows.length, 11); r++) {
      const numbers = rows[r - 1].filter((cell) => cell !== "" && !parseCell(cell).error).length;
      if (numbers >= 2) return 0;  // readings above: no table starts below them
      if (namesPositions(rows[r])) return r;
    }
    return 0;
  }

  // Both parts' tables pasted, each under a title that names its part (the handout's
  // "表 1 …水平面内…", "表 2 …竖直面内…", "Part B"): this part's table alone, as
  // app.core.part_names reads a file; a second table under a title that names no part is
  // left out at its repeated header, never read as readings.
  function partNamed(text) {
    const flat = text.toLowerCase().replace(/\s+/g, "");
    const named = Object.keys(config.partWords).filter((part) =>
      flat === config.partLetters[part] || config.partWords[part].some((word) => flat.includes(word)));
    return named.length === 1 ? named[0] : null;
  }
  function ownTable(rows, part) {
    const titles = [];
    rows.forEach((row, r) => {
      const cells = row.filter((cell) => cell !== "");
      const named = cells.some((cell) => !parseCell(cell).error) ? null : partNamed(cells.join(" "));
      if (named) titles.push([r, named]);
    });
    const own = titles.filter(([, named]) => named === part);
    if (new Set(titles.map(([, named]) => named)).size < 2 || own.length !== 1) return null;
    const at = titles.findIndex(([r]) => r === own[0][0]);
    const end = at + 1 < titles.length ? titles[at + 1][0] : rows.length;
    return rows.slice(own[0][0] + 1, end);
  }
  const sameRow = (a, b) => a.join("\t").replace(/\t+$/, "") === b.join("\t").replace(/\t+$/, "");

  // A table turned on its side: one row per position, its name first ("位置1 | 10.74 | 10.65 …"),
  // the name ended by a colon or "=" as notes are typed ("位置1：10.74 …", "P1 = 10.74, 10.65")
  // -- app.core.readings reads a file of it so.  Each position's readings go down its column.
  const LABEL_MARK = /\s*[:=]\s*/;
  function labelApart(row) {
    for (let end = 0; end < Math.min(3, row.length); end++) {
      const mark = LABEL_MARK.exec(row[end]);
      if (mark) {
        const label = [...row.slice(0, end), row[end].slice(0, mark.index)].join(" ").trim();
        const first = row[end].slice(mark.index + mark[0].length);
        return [label, ...(first ? [first] : []), ...row.slice(end + 1)];
      }
    }
    return row;
  }
  const CHINESE_DIGITS = "一二三四五六七八九十";
  function positionNamed(cell) {
    const name = headerName(cell);
    const named = POSITION_NAMES.map((pattern) => name.match(pattern)).find(Boolean);
    if (!named) return NaN;
    return /^\d+$/.test(named[1]) ? Number(named[1]) : CHINESE_DIGITS.indexOf(named[1]) + 1;
  }
  function turnedBlock(rows, columns) {
    const turnedRow = (row) => positionNamed(row[0] || "") >= 1 &&
      row.slice(1).every((cell) => cell === "" || !isText(cell));
    let named = rows.map(labelApart);
    let header = null;  // "位置 | 1 | 2 | … | 平均值" over the rows: it numbers the readings
    if (named.length > 2 && !turnedRow(named[0]) && named.slice(1).every(turnedRow)) {
      header = named[0];
      named = named.slice(1);
    }
    if (named.length < 2 || !named.every(turnedRow)) return null;
    const summaries = new Set((header || []).flatMap((cell, k) => (k > 0 && isSummary([cell]) ? [k] : [])));
    let numbers = named.map((row) => positionNamed(row[0]));
    // 1-2-3-4-4-3-2-1, each named again on its second visit: positions 5-8 (readings_data.symmetric_numbers)
    if (numbers.join() === "1,2,3,4,4,3,2,1") numbers = [1, 2, 3, 4, 5, 6, 7, 8];
    const readings = named.map((row) => row.filter((cell, k) => k > 0 && !summaries.has(k) && cell !== ""));
    if (!numbers.every((n) => n <= columns) || new Set(numbers).size !== numbers.length ||
        !readings.every((cells) => cells.length > 0)) {
      return null;
    }
    const length = Math.max(...readings.map((cells) => cells.length));
    const width = Math.max(...numbers);
    const block = Array.from({ length }, () => new Array(width).fill(undefined));
    readings.forEach((cells, i) => cells.forEach((value, r) => { block[r][numbers[i] - 1] = value; }));
    return { block, summaries: summaries.size > 0 };
  }

  // A header cell that names times: "time", "t", "时间", a time's word ("Elapsed Time",
  // "seconds_elapsed") or its unit ("Zeit (s)") -- app.core.record_columns.time_column.
  const TIME_WORDS = /^(?:t|timestamp|datetime|date_time|sampletimefine)$|(?:^|[^a-z])(?:time|elapsed|zeit|tiempo)(?:$|[^a-z])|时间|时刻|历时/;
  const TIME_UNIT = /[(\[（【]\s*(?:s|sec|ms|us|µs|μs|ns|秒)\s*[)\]）】]$|_(?:s|ms|us|ns)$/;
  const namesTime = (cell) => TIME_WORDS.test(headerName(cell)) || TIME_UNIT.test(plain(cell).trim().toLowerCase());

  function parseBlock(text, columns, part) {
    const lines = plain(text).replace(/\r\n?/g, "\n").split("\n").filter((line) => line.trim() !== "");
    let rows = splitLines(lines);
    const notes = [];
    const own = part ? ownTable(rows, part) : null;
    if (own) {
      rows = own;
      notes.push("js.own_table_taken");
    }
    const above = linesAbove(rows);
    if (above) {
      rows = rows.slice(above);
      notes.push("js.lines_above_skipped");
    }
    const turned = turnedBlock(rows, columns);
    if (turned) {
      notes.push("js.turned_table");
      let { block } = turned;
      // each row's mean in its last cell, unlabelled: the block's last row is the means
      const means = isRowOfMeans(block.map((row) => row.map((cell) => cell ?? "")));
      if (means) block = block.slice(0, -1);
      if (turned.summaries || means) notes.push("js.summary_column_skipped");
      return { rows: block, notes, whole: true, named: namedRateUnit(rows.map((row) => labelApart(row)[0]), null) };
    }
    let header = null;
    let unitsRow = null;
    let body = rows;
    if (body.length && (rows[0].some(isText) ||
        (body.length > 1 && numbersThePositions(rows[0])))) {
      header = body[0];
      body = body.slice(1);
      notes.push("js.header_skipped");
      if (body.length && isUnitsRow(body[0])) {  // "s, °/h…": a note
        unitsRow = body[0];
        body = body.slice(1);
      }
    }
    if (header && header.some(isText) && header.filter((cell) => cell !== "").length > 1) {  // a second table's
      const again = body.findIndex((row) => sameRow(row, header));
      if (again >= 0) {
        body = body.slice(0, again);
        while (body.length && !body[body.length - 1].some((cell) => cell !== "" && !isText(cell))) {
          body.pop();  // the second table's title above its header
        }
        notes.push("js.second_table_skipped");
      }
    }
    const angles = header && headerAngles(header);
    const expected = (config.angles[part] || []).slice(0, angles ? angles.length : 0);
    if (angles && turnedOtherWay(angles, expected)) {  // read in column order all the same
      notes.push(["js.header_angles_other_way", { header: degrees(angles), session: degrees(expected), count: expected.length }]);
    }
    const long = header && longColumns(header);
    if (long) {  // each position's readings to its own column, from the grid's first
      notes.push("js.long_block");
      const block = body.filter((row) => !isSummary(row));
      if (long.byAngle) {  // used as given, clockwise positive: said where they run the other way
        const given = [...new Set(block.map((row) => (row[long.key] || "").trim()))]
          .map(angleOf);
        const turns = (config.angles[part] || []).slice(0, given.length);
        if (turnedOtherWay(given, turns)) {
          notes.push(["js.long_angles_other_way", { header: degrees(given), session: degrees(turns), count: turns.length }]);
        }
      }
      return { rows: longBlock(block, long, columns, part), notes, whole: true, named: namedRateUnit(header, unitsRow) };
    }
    // One position's record copied from a logger's sheet ("Time (s) | Rate (°/h)"): its
    // times are no position's readings; with several axes beside them (an IMU's "time | gx |
    // gy | gz") which is the gyro's cannot be told here -- the file method asks
    // (app.core.record_columns.names_a_records_times).
    if (header && !header.some(namesPosition) && namesTime(header[0] || "")) {
      const kept = header.slice(1).filter((cell) => cell !== "").length;
      if (kept !== 1) return { rows: [], notes, problem: "js.record_of_axes", named: { unit: null, unread: null } };
      body = body.map((row) => row.slice(1));
      notes.push("js.time_column_skipped");
      return { rows: body.filter((row) => !isSummary(row)), notes, named: namedRateUnit(header, unitsRow) };
    }
    const summaries = body.filter(isSummary).length;
    if (summaries) {
      body = body.filter((row) => !isSummary(row));
      notes.push("js.summary_rows_skipped");
    }
    // Columns before the first position's: a row number, a time, the handout's label column.
    let skip = 0;
    let note = "js.leading_columns_skipped";
    if (header && header.some(namesPosition)) {
      skip = header.findIndex(namesPosition);
      if (skip === 1 && ROW_NUMBER_NAMES.has((header[0] || "").toLowerCase())) note = "js.row_numbers_skipped";
    } else if (header && ROW_NUMBER_NAMES.has((header[0] || "").toLowerCase())) {
      skip = 1;
      note = "js.row_numbers_skipped";
    } else {
      const firstColumn = body.map((row) => row[0]);
      const counts = body.length > 1 && body[0].length > 1 && /^[01]$/.test(firstColumn[0]) &&
        firstColumn.every((cell, i) => cell === String(i + Number(firstColumn[0])));
      const labels = body.length > 0 && body[0].length > 1 && firstColumn.some((cell) => cell !== "") &&
        firstColumn.every((cell) => cell === "" || isText(cell));  // "采样值" beside the rows
      if (counts || labels) skip = 1;
      if (counts) note = "js.row_numbers_skipped";
    }
    if (skip > 0) {
      body = body.map((row) => row.slice(skip));
      notes.push(note);
    }
    if (isRowOfMeans(body)) {
      body = body.slice(0, -1);
      notes.push("js.means_row_skipped");
    }
    return { rows: body, notes, named: namedRateUnit(header, unitsRow) };
  }

  // A last row that is each column's mean of the rows above it, written to more decimals
  // than they are: a spreadsheet's =AVERAGE row without a label (app.core.means_row).
  function writtenDecimals(text, significant = false) {
    const match = /^[-+]?(\d*)(?:\.(\d*))?(?:[eE]([-+]?\d+))?$/.exec(text);
    if (!match || !(match[1] || match[2])) return null;
    const fraction = significant ? (match[2] || "").replace(/0+$/, "") : (match[2] || "");
    return fraction.length - Number(match[3] || 0);
  }
  function isRowOfMeans(rows) {
    if (rows.length < 2) return false;
    const last = rows[rows.length - 1].map(numberText);
    const width = Math.max(...rows.map((row) => row.length));
    let longer = false;
    for (let c = 0; c < width; c++) {
      const above = rows.slice(0, -1).map((row) => numberText(row[c] || "")).filter((cell) => cell !== "");
      const decimals = writtenDecimals(last[c] || "");
      if (decimals === null || above.length < 3) return false;
      const values = above.map((cell) => parseCell(cell));
      if (values.some((parsed) => parsed.error)) return false;
      const mean = values.reduce((sum, parsed) => sum + parsed.value, 0) / values.length;
      if (Math.abs(Number(last[c]) - mean) > 0.5 * 10 ** -decimals + 1e-12 * Math.max(1, Math.abs(mean))) return false;
      const finer = writtenDecimals(last[c], true);  // "6.020" is no finer than "6.02"
      longer = longer || above.every((cell) => finer > (writtenDecimals(cell, true) ?? 0));
    }
    return longer;
  }

  // Cells of each line: tabs (a spreadsheet's copy), else semicolons, else 、 (the comma a
  // Chinese input method types), else commas -- unless every line has one comma and no
  // point ("10,74": a decimal comma) -- else blanks.
  function splitLines(lines) {
    const all = lines.join("\n");
    let split;
    if (all.includes("\t")) split = (line) => line.split("\t");
    else if (all.includes(";")) split = (line) => line.split(";");
    else if (all.includes("\u3001")) split = (line) => line.split("\u3001");
    else if (all.includes(",") && !(lines.every((line) => (line.match(/,/g) || []).length === 1) && !all.includes("."))) split = (line) => line.split(",");
    else return spacedCells(lines);
    return lines.map((line) => split(line).map((cell) => cell.trim()));
  }
  // Columns between spaces, as app.core.spreadsheet_text.spaced_cells splits a file: a
  // line of names holding single spaces ("Position 1   Position 2") at runs of two where
  // that gives the rows' width; a label column's empty cells, lost between spaces, given
  // back to the rows of numbers ("位置 1 2 3 4" over "10.74 2.88 …").
  function spacedCells(lines) {
    const isNumber = (cell) => /^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$/.test(cell);
    let split = lines.map((line) => line.trim().split(/\s+/).filter(Boolean));
    const widths = split.filter((cells) => cells.length && cells.every(isNumber)).map((cells) => cells.length);
    if (!widths.length) return split;
    const counts = new Map();  // the rows' most common width, counted once (a logger's 60,000 lines)
    widths.forEach((w) => counts.set(w, (counts.get(w) || 0) + 1));
    const width = [...counts.entries()].reduce((best, entry) => (entry[1] > best[1] ? entry : best))[0];
    split = split.map((cells, i) => {
      if (cells.length === width || cells.every(isNumber)) return cells;
      const wide = lines[i].trim().split(/\s{2,}/).filter(Boolean);
      return wide.length === width ? wide : cells;
    });
    if (split.some((cells) => cells.length === width + 1 && !isNumber(cells[0]))) {
      split = split.map((cells) => (cells.length === width && cells.every(isNumber) ? ["", ...cells] : cells));
    }
    return split;
  }

  function setupGrid(panel) {
    const body = panel.querySelector("tbody");
    const status = panel.querySelector(".grid-status");
    const columns = panel.querySelectorAll("thead th").length - 1;

    // Rows built off the page, their chosen column marked as they are made, and added at
    // once: asking the live table for its row count after each row, then marking every
    // cell of the grid again, made a 60,000-row paste take 28 s.
    function addRows(count) {
      const first = body.rows.length;
      const chosen = selected[panel.dataset.part];
      const names = Array.from({ length: columns }, (_, c) => t("js.position", { n: c + 1 }));
      const rows = document.createDocumentFragment();
      for (let i = 0; i < count; i += 1) {
        const number = first + i + 1;
        const row = document.createElement("tr");
        const label = document.createElement("th");
        label.textContent = String(number);
        row.appendChild(label);
        for (let c = 0; c < columns; c += 1) {
          const cell = document.createElement("td");
          const input = document.createElement("input");
          input.inputMode = "decimal";
          input.autocomplete = "off";
          input.enterKeyHint = "next";
          input.dataset.column = String(c + 1);
          input.setAttribute("aria-label", `${names[c]} #${number}`);
          if (c + 1 === chosen) cell.classList.add("column-selected");
          cell.appendChild(input);
          row.appendChild(cell);
        }
        rows.appendChild(row);
      }
      body.appendChild(rows);
    }

    function cellAt(row, column) {
      return body.rows[row]?.querySelectorAll("input")[column] || null;
    }

    function validate() {
      let problem = null;
      let count = 0;
      body.querySelectorAll("input").forEach((input) => {
        const parsed = parseCell(input.value);
        input.classList.toggle("invalid", Boolean(parsed.error));
        input.setAttribute("aria-invalid", String(Boolean(parsed.error)));
        input.title = parsed.error ? t(parsed.error, { value: input.value }) : "";
        if (parsed.error && !problem) {
          problem = `${t("js.position", { n: input.dataset.column })}, #${input.closest("tr").rowIndex}: ${t(parsed.error, { value: input.value.trim() })}`;
        }
        if (parsed.value !== undefined) count += 1;
      });
      status.textContent = problem || (count ? t("js.grid_ok", { n: count }) : "");
      status.classList.toggle("error-text", Boolean(problem));
      return !problem;
    }

    body.addEventListener("input", validate);
    // a number typed in full-width forms shows as it will be saved once the cell is left
    body.addEventListener("change", (event) => {
      const input = event.target.closest("input");
      if (input && /[^\x00-\x7f]/.test(input.value) && !parseCell(input.value).error) {
        input.value = plain(input.value).trim();
      }
    });
    // Enter and the arrow keys move like a spreadsheet: Enter (and ↓) down a column, ↑ up,
    // ← → across when the caret is at the edge of the cell.  A new row appears at the end.
    body.addEventListener("keydown", (event) => {
      const input = event.target.closest("input");
      if (!input || event.altKey || event.ctrlKey || event.metaKey) return;
      const row = input.closest("tr").sectionRowIndex;
      const column = Number(input.dataset.column) - 1;
      let target = null;
      if (event.key === "Enter" || event.key === "ArrowDown") {
        const step = event.key === "Enter" && event.shiftKey ? -1 : 1;
        if (step > 0 && row + 1 >= body.rows.length) addRows(1);
        target = cellAt(row + step, column);
      } else if (event.key === "ArrowUp") {
        target = cellAt(row - 1, column);
      } else if (event.key === "ArrowLeft" && input.selectionStart === 0 && (input.selectionEnd === 0 || input.selectionEnd === input.value.length)) {
        target = cellAt(row, column - 1); // caret at the start, or the cell just entered (all selected)
      } else if (event.key === "ArrowRight" && input.selectionEnd === input.value.length && (input.selectionStart === 0 || input.selectionStart === input.value.length)) {
        target = cellAt(row, column + 1);
      } else {
        return;
      }
      event.preventDefault();
      if (target) {
        target.focus();
        target.select();
      }
    });
    // A paste longer than the grid shows (a logger's export): its readings are held and
    // saved as pasted; building hundreds of thousands of cells froze the page for seconds.
    let held = null;
    function holdLongPaste(rows, startColumn, notes) {
      const values = {};
      for (let r = 0; r < rows.length; r += 1) {
        for (let c = 0; c < rows[r].length; c += 1) {
          const column = startColumn + c + 1;
          const parsed = parseCell(rows[r][c] ?? "");
          if (parsed.empty || column > columns) continue;
          if (parsed.error) {
            held = null;
            status.textContent = t("js.long_paste_bad", { rows: rows.length, row: r + 1, position: column, problem: t(parsed.error, { value: rows[r][c] }) });
            status.classList.add("error-text");
            return;
          }
          (values[column] = values[column] || []).push(parsed.value);
        }
      }
      held = values;
      const counts = Object.entries(values).map(([position, list]) => `${t("js.position", { n: position })}: n = ${list.length}`);
      status.textContent = [t("js.long_paste_held", { rows: rows.length, counts: counts.join(", ") }), ...notes.map(said)].join(" ");
      status.classList.remove("error-text");
    }
    body.addEventListener("paste", (event) => {
      const target = event.target.closest("input");
      const text = (event.clipboardData || window.clipboardData).getData("text");
      if (!target || !/[\t\n;]|,.*,|\s\S/.test(plain(text).trim())) return;
      event.preventDefault();
      const { rows, notes, whole, named, problem } = parseBlock(text, columns, panel.dataset.part);
      if (problem) {
        held = null;
        status.textContent = t(problem);
        status.classList.add("error-text");
        return;
      }
      const unit = panel.querySelector(".unit");
      // °/s typed as °/h: 3600 times too small; mdeg/s as either: wrong by a factor
      const clash = Boolean(named.unread) || (named.unit !== null && named.unit !== unit.value);
      if (named.unread) {
        notes.push(["js.unit_unread", { unit: named.unread }]);
      } else if (clash) {
        const symbol = (value) => [...unit.options].find((option) => option.value === value).textContent;
        notes.push(["js.unit_named_other", { named: symbol(named.unit), chosen: symbol(unit.value) }]);
      }
      const startRow = whole ? 0 : target.closest("tr").sectionRowIndex;
      const startColumn = whole ? 0 : Number(target.dataset.column) - 1;
      if (startRow + rows.length > config.gridLimit) {
        holdLongPaste(rows, startColumn, notes);
        return;
      }
      held = null;
      const needed = startRow + rows.length - body.rows.length;
      if (needed > 0) addRows(needed);
      let dropped = 0;
      rows.forEach((cells, r) => {
        cells.forEach((value, c) => {
          if (value === undefined) return;  // a long table's position not in the paste
          const input = cellAt(startRow + r, startColumn + c);
          if (input) input.value = value;
          else if (value !== "") dropped += 1;
        });
      });
      validate();
      const extra = notes.map(said);
      if (dropped) extra.push(t("js.cells_dropped", { n: dropped, columns }));
      status.textContent = `${t("js.pasted", { rows: rows.length })} ${extra.join(" ")} ${status.textContent}`.trim();
      status.classList.toggle("error-text", Boolean(dropped) || clash || status.classList.contains("error-text"));
    });
    panel.querySelector(".add-rows").addEventListener("click", () => addRows(5));
    panel.querySelector(".clear-grid").addEventListener("click", () => {
      held = null;
      body.querySelectorAll("input").forEach((input) => { input.value = ""; });
      validate();
    });
    // The readings already saved come back into the grid, so that a typo is corrected in
    // place.  Only the columns that differ from what was loaded are saved (each as a new
    // take; the old one stays in the history); a change of unit changes them all.
    const unitSelect = panel.querySelector(".unit");
    let loaded = { unit: null, columns: {} };
    function columnValues(column) {
      const values = [];
      body.querySelectorAll(`input[data-column="${column}"]`).forEach((input) => {
        const parsed = parseCell(input.value);
        if (parsed.value !== undefined) values.push(parsed.value);
      });
      return values;
    }
    async function loadSaved() {
      let saved;
      try {
        const response = await fetch(`${base}/grid.json?part=${panel.dataset.part}`, { headers: { Accept: "application/json" } });
        if (!response.ok) return;
        saved = await response.json();
      } catch (error) {
        return;
      }
      const shown = [];
      const notes = [];
      const longest = Math.max(0, ...Object.values(saved.positions).map((p) => (p.values || []).length));
      if (longest > body.rows.length) addRows(longest - body.rows.length);
      Object.entries(saved.positions).forEach(([position, entry]) => {
        if (!entry.values) {
          notes.push(t("js.grid_not_loaded", { position, n: entry.n }));
          return;
        }
        entry.values.forEach((value, row) => { cellAt(row, Number(position) - 1).value = String(value); });
        loaded.columns[position] = entry.values;
        shown.push(position);
      });
      if (shown.length) {
        loaded.unit = saved.unit;
        if ([...unitSelect.options].some((option) => option.value === saved.unit)) unitSelect.value = saved.unit;
      }
      validate();
      const parts = [];
      if (shown.length) parts.push(t("js.grid_loaded", { positions: shown.join(", ") }));
      status.textContent = [...parts, ...notes, status.textContent].join(" ").trim();
    }
    function changedColumns() {
      const data = {};
      for (let column = 1; column <= columns; column += 1) {
        const values = columnValues(column);
        if (!values.length) continue;
        const before = loaded.columns[column];
        const same = before && unitSelect.value === loaded.unit && before.length === values.length &&
          before.every((value, i) => value === values[i]);
        if (!same) data[column] = values;
      }
      return data;
    }

    panel.querySelector(".save-manual").addEventListener("click", async () => {
      if (held) {
        status.textContent = t("js.saving");
        try {
          await postJson("/manual", { part: panel.dataset.part, unit: unitSelect.value, columns: held });
          held = null;
          status.textContent = t("js.saved");
          reloadSoon();
        } catch (error) {
          status.textContent = error.message;
          status.classList.add("error-text");
        }
        return;
      }
      if (!validate()) return;
      const data = changedColumns();
      if (!Object.keys(data).length) {
        const anything = [...body.querySelectorAll("input")].some((input) => input.value.trim() !== "");
        status.textContent = t(anything ? "js.grid_unchanged" : "js.grid_empty");
        status.classList.add("error-text");
        return;
      }
      status.textContent = t("js.saving");
      try {
        await postJson("/manual", { part: panel.dataset.part, unit: panel.querySelector(".unit").value, columns: data });
        status.textContent = t("js.saved");
        reloadSoon();
      } catch (error) {
        status.textContent = error.message;
        status.classList.add("error-text");
      }
    });
    addRows(Math.max(10, config.minReadings));
    markColumn(panel.querySelector(".readings-grid"), selected[panel.dataset.part]);
    loadSaved();
  }
  document.querySelectorAll('.method-panel[data-method="manual"]').forEach(setupGrid);

  // --- CSV file ---------------------------------------------------------------------------
  // UTF-8 first, then GB18030 (what a Chinese-locale Excel saves), then Windows-1252 (a
  // Western Windows program's "°/s"); UTF-16 by its mark, or without one by the zero high
  // bytes of its ASCII characters -- as the server reads a file (text_files.py).
  function utf16WithoutMark(bytes) {
    const count = Math.min(4096, bytes.length - (bytes.length % 2));
    if (count < 4) return null;
    let evenZeros = 0;
    let oddZeros = 0;
    for (let i = 0; i < count; i += 2) {
      if (bytes[i] === 0) evenZeros += 1;
      if (bytes[i + 1] === 0) oddZeros += 1;
    }
    const half = count / 2;
    if (oddZeros >= 0.5 * half && evenZeros <= 0.05 * half) return "utf-16le";
    if (evenZeros >= 0.5 * half && oddZeros <= 0.05 * half) return "utf-16be";
    return null;
  }

  function decodeFile(buffer) {
    const bytes = new Uint8Array(buffer);
    if (bytes[0] === 0xff && bytes[1] === 0xfe) return new TextDecoder("utf-16le").decode(bytes);
    if (bytes[0] === 0xfe && bytes[1] === 0xff) return new TextDecoder("utf-16be").decode(bytes);
    const unmarked = utf16WithoutMark(bytes);
    if (unmarked) return new TextDecoder(unmarked).decode(bytes);
    for (const encoding of ["utf-8", "gb18030"]) {
      try {
        return new TextDecoder(encoding, { fatal: true }).decode(bytes);
      } catch (error) {
        // the next encoding
      }
    }
    return new TextDecoder("windows-1252").decode(bytes);
  }

  // A file the server reads as text: an Excel workbook (.xlsx is a zip, "PK\x03\x04", as
  // NumPy's .npz is; .xls an OLE file), a MATLAB data file ("MATLAB"), a NumPy array
  // ("\x93NUMPY").
  function isBinaryTable(buffer) {
    const head = new Uint8Array(buffer, 0, Math.min(6, buffer.byteLength));
    const starts = (magic) => magic.every((byte, i) => head[i] === byte);
    return starts([0x50, 0x4b, 0x03, 0x04]) || starts([0xd0, 0xcf, 0x11, 0xe0])
      || starts([0x4d, 0x41, 0x54, 0x4c, 0x41, 0x42]) || starts([0x93, 0x4e, 0x55, 0x4d, 0x50, 0x59]);
  }

  function setupCsv(panel) {
    const input = panel.querySelector(".csv-file");
    const preview = panel.querySelector(".csv-preview");
    const accept = panel.querySelector(".accept-csv");
    let text = null;
    let recordPosition = null;  // a one-position record: the position it is saved as
    let recordColumn = null;  // an IMU's record of several axes: the gyro's column
    let columnChoices = [];  // the columns the file offers ({value, label})
    let sheet = null;  // an Excel workbook: the sheet read
    let sheets = [];  // …and the sheets that hold readings, where the student may choose

    function body() {
      const data = { part: panel.dataset.part, unit: panel.querySelector(".unit").value, text };
      if (recordPosition !== null) data.position = recordPosition;
      if (recordColumn !== null) data.column = recordColumn;
      return data;
    }

    // A choice the file leaves to the student, beside the preview: a labelled select.
    function labelledChoice(labelKey, className, options, value, chosen) {
      const label = document.createElement("label");
      label.className = "inline-label";
      label.textContent = t(labelKey) + " ";
      const select = document.createElement("select");
      select.className = className;
      options.forEach((choice) => {
        const option = document.createElement("option");
        option.value = choice.value;
        option.textContent = choice.label;
        select.appendChild(option);
      });
      select.value = value;
      select.addEventListener("change", () => {
        chosen(select.value);
        showPreview(true);
      });
      label.appendChild(select);
      return label;
    }

    // An IMU's record of several axes: which column is the gyro's, chosen here.
    const columnChoice = () => labelledChoice("js.record_column", "record-column", columnChoices,
      recordColumn, (value) => { recordColumn = value; });

    // An Excel workbook of several sheets of readings (one a part, say): which, chosen here.
    const sheetChoice = () => labelledChoice("js.workbook_sheet", "workbook-sheet",
      sheets.map((name) => ({ value: name, label: name })), sheet, (value) => {
        sheet = value;
        recordPosition = null;
        recordColumn = null;
        columnChoices = [];
      });

    // A one-position record (a gyro logger's file): which position it is, chosen here.
    const positionChoice = (result) => labelledChoice("js.record_position", "record-position",
      Array.from({ length: result.position_count }, (_, k) => ({ value: String(k + 1), label: String(k + 1) })),
      String(recordPosition), (value) => { recordPosition = Number(value); });

    async function showPreview(keepFile) {
      accept.disabled = true;
      preview.textContent = "";
      if (keepFile !== true) {
        recordPosition = null;
        recordColumn = null;
        columnChoices = [];
        sheet = null;
        sheets = [];
      }
      const file = input.files[0];
      if (!file) return;
      if (file.size > MAX_FILE_BYTES) {
        preview.innerHTML = `<p class="error-text">${t("js.too_large")}</p>`;
        return;
      }
      const buffer = await file.arrayBuffer();
      try {
        if (isBinaryTable(buffer)) {  // its sheet or vectors of readings, as text, from the server
          const query = new URLSearchParams({ part: panel.dataset.part });
          if (sheet !== null) query.set("sheet", sheet);
          const book = await postBytes(`/csv/binary?${query}`, buffer);
          ({ text, sheet, sheets } = book);
        } else {
          // Ctrl-Z or NUL bytes after the last line (DOS's end of file, a logger's
          // unwritten space) are not text: not sent (the server passes them over too)
          text = decodeFile(buffer).replace(/[\x1a\x00]+$/, "");
        }
        const result = await postJson("/csv/preview", body());
        if (result.layout === "record") recordPosition = result.positions[0].position;
        columnChoices = result.columns || [];
        recordColumn = result.column ?? null;
        const rows = result.positions.map((p) =>
          `<tr><td>${p.position}</td><td class="num">${p.angle_deg}°</td><td class="num">${p.n}</td><td class="num">${p.mean_deg_h.toFixed(3)}</td><td>${p.first.map((v) => v.toFixed(3)).join(", ")}…</td></tr>`).join("");
        preview.innerHTML = `<p>${t("js.preview_title")}</p><table class="table compact"><thead><tr><th>#</th><th class="num">${t("js.angle")}</th><th class="num">n</th><th class="num">${t("js.mean")}</th><th>${t("js.samples")}</th></tr></thead><tbody>${rows}</tbody></table>`;
        if (result.layout === "record") preview.prepend(positionChoice(result));
        if (columnChoices.length) preview.prepend(columnChoice());
        if (sheets.length > 1) preview.prepend(sheetChoice());
        (result.notes || []).forEach((note) => {  // a row of means passed over: said, not read
          const line = document.createElement("p");
          line.className = "muted";
          line.textContent = note;
          preview.appendChild(line);
        });
        accept.disabled = false;
      } catch (error) {
        const message = document.createElement("p");
        message.className = "error-text";
        message.textContent = error.message;
        preview.replaceChildren(message);
        // a column chosen that cannot be read (a counter, say): another can still be chosen
        if (columnChoices.length && recordColumn !== null) preview.prepend(columnChoice());
        if (sheets.length > 1) preview.prepend(sheetChoice());  // and another sheet
      }
    }
    input.addEventListener("change", showPreview);
    panel.querySelector(".unit").addEventListener("change", () => showPreview(true));
    accept.addEventListener("click", async () => {
      accept.disabled = true;
      try {
        await postJson("/csv", body());
        preview.textContent = t("js.saved");
        reloadSoon();
      } catch (error) {
        preview.textContent = error.message;
        accept.disabled = false;
      }
    });
  }
  document.querySelectorAll('.method-panel[data-method="csv"]').forEach(setupCsv);

  // --- simulated gyro ---------------------------------------------------------------------
  function updateTurnHint(part) {
    const panel = document.querySelector(`.method-panel[data-method="simulator"][data-part="${part}"]`);
    if (!panel) return;
    panel.querySelector(".table-position").textContent = String(config.table[part]);
    const ready = config.table[part] === selected[part];
    panel.querySelector(".turn").disabled = ready;
    panel.querySelector(".start-sim").disabled = !ready || panel.dataset.busy === "1";
    panel.querySelector(".sim-status").textContent = ready ? "" : t("js.turn_needed", { n: selected[part] });
  }

  function setupSimulator(panel) {
    const part = panel.dataset.part;
    const status = panel.querySelector(".sim-status");
    const progress = panel.querySelector(".sim-progress");
    const startButton = panel.querySelector(".start-sim");
    const stopButton = panel.querySelector(".stop-sim");
    const chart = panel.querySelector(".live-chart");
    const trimBox = panel.querySelector(".trim-box");
    const trimRange = panel.querySelector(".trim-range");
    let socket = null;
    let saved = false;
    let recorded = { t: [], v: [], position: 0 };

    // Running n, mean, σ and σ/√n (Welford), from the first reading kept.
    function showStats(values) {
      let n = 0, mean = 0, m2 = 0;
      for (const value of values) {
        n += 1;
        const delta = value - mean;
        mean += delta / n;
        m2 += delta * (value - mean);
      }
      const sigma = n > 1 ? Math.sqrt(m2 / (n - 1)) : NaN;
      const show = (selector, value, digits) => {
        panel.querySelector(selector).textContent = Number.isFinite(value) ? value.toFixed(digits) : "—";
      };
      panel.querySelector(".live-n").textContent = String(n);
      show(".live-mean", n ? mean : NaN, 3);
      show(".live-sigma", sigma, 3);
      show(".live-se", sigma / Math.sqrt(n), 4);
    }

    function markTrim(count) {
      const cut = recorded.t[count] ?? recorded.t[0];
      if (chart.data) Plotly.relayout(chart, {
        shapes: count > 0 ? [{ type: "rect", xref: "x", yref: "paper", x0: recorded.t[0], x1: cut, y0: 0, y1: 1,
          fillcolor: "#d1495b", opacity: 0.15, line: { width: 0 } }] : [],
      });
      panel.querySelector(".trim-shown").textContent = t("js.trim_shown", { n: count, s: (cut - recorded.t[0]).toFixed(1) });
      showStats(recorded.v.slice(count));
    }

    trimRange.addEventListener("input", () => markTrim(Number(trimRange.value)));
    panel.querySelector(".keep-all").addEventListener("click", () => reloadSoon());
    panel.querySelector(".save-trim").addEventListener("click", async () => {
      try {
        await postJson("/trim", { part, position: recorded.position, trim: Number(trimRange.value) });
        reloadSoon();
      } catch (error) {
        status.textContent = error.message;
      }
    });

    const projector = panel.querySelector(".projector-toggle");
    function setProjector(on) {
      panel.querySelector(".live-panel").classList.toggle("projector", on);
      projector.setAttribute("aria-pressed", String(on));
      projector.textContent = t(on ? "js.projector_exit" : "js.projector");
      if (window.Plotly && chart.data) Plotly.Plots.resize(chart);
    }
    projector.addEventListener("click", () => setProjector(projector.getAttribute("aria-pressed") !== "true"));
    document.addEventListener("keydown", (event) => { if (event.key === "Escape") setProjector(false); });

    panel.querySelector(".turn").addEventListener("click", async () => {
      try {
        await postJson("/turn", { part, position: selected[part] });
        config.table[part] = selected[part];
        updateTurnHint(part);
        status.textContent = t("js.turned", { n: selected[part] });
        if (!startButton.disabled) startButton.focus();  // the turn button is now disabled
      } catch (error) {
        status.textContent = error.message;
      }
    });

    const planeButton = panel.querySelector(".set-plane");
    if (planeButton) {
      planeButton.addEventListener("click", async () => {
        const planeStatus = panel.querySelector(".plane-status");
        const value = Number(panel.querySelector(".plane-dial").value);
        if (panel.querySelector(".plane-dial").value.trim() === "" || !Number.isFinite(value)) {
          planeStatus.textContent = t("js.not_a_number");
          return;
        }
        try {
          const reply = await postJson("/plane", { dial_deg: value });
          planeStatus.textContent = t("js.plane_set", { dial: reply.dial_deg });
        } catch (error) {
          planeStatus.textContent = error.message;
        }
      });
    }

    function finish(message) {
      panel.dataset.busy = "0";
      stopButton.disabled = true;
      updateTurnHint(part);
      if (message) status.textContent = message;
    }

    startButton.addEventListener("click", () => {
      const scheme = window.location.protocol === "https:" ? "wss" : "ws";
      socket = new WebSocket(`${scheme}://${window.location.host}${base}/stream`);
      saved = false;
      panel.dataset.busy = "1";
      startButton.disabled = true;
      socket.addEventListener("open", () => {
        socket.send(JSON.stringify({
          action: "start", part, position: selected[part],
          dwell_s: Number(panel.querySelector(".dwell").value),
          settle_s: Number(panel.querySelector(".settle").value),
          speed: Number(panel.querySelector(".speed").value),
        }));
      });
      socket.addEventListener("message", (event) => {
        const frame = JSON.parse(event.data);
        if (frame.type === "started") {
          progress.max = frame.total;
          progress.value = 0;
          stopButton.disabled = false;
          if (document.activeElement === document.body || document.activeElement === startButton) stopButton.focus();
          status.textContent = t("js.recording", { n: frame.position });
          recorded = { t: [], v: [], position: frame.position };
          trimBox.hidden = true;
          panel.querySelector(".live-title").textContent = t("js.position", { n: frame.position });
          showStats([]);
          // the live chart starts with what has arrived by the time plotly is here
          GyroCharts.plotly().then((P) => P.newPlot(chart, [{ x: recorded.t.slice(-LIVE_WINDOW), y: recorded.v.slice(-LIVE_WINDOW), mode: "lines", type: "scatter", line: { width: 1 } }], {
            margin: { l: 60, r: 10, t: 10, b: 40 }, height: 220,
            xaxis: { title: { text: t("chart.time_s") } }, yaxis: { title: { text: t("chart.rate_deg_h") } },
          }, GyroCharts.options)).catch(() => {});
        } else if (frame.type === "samples") {
          if (chart.data) Plotly.extendTraces(chart, { x: [frame.t], y: [frame.v] }, [0], LIVE_WINDOW);
          progress.value = frame.done;
          recorded.t.push(...frame.t);
          recorded.v.push(...frame.v);
          showStats(recorded.v);
        } else if (frame.type === "saved") {
          saved = true;
          remember(part, { position: Math.min(frame.position + 1, 4) });
          finish(t("js.done_trim", { n: frame.n }));
          socket.close();
          // the position is stored now: its step says so before any reload
          const step = document.querySelector(`.step[data-part="${part}"][data-position="${frame.position}"]`);
          if (step) {
            step.classList.add("done");
            step.querySelector(".step-status").textContent = `n = ${frame.n} · ${t("source.simulator")}`;
          }
          // the whole recording, for choosing where the transient ends (or keeping it all)
          if (chart.data) Plotly.react(chart, [{ x: recorded.t, y: recorded.v, mode: "lines", type: "scatter", line: { width: 1 } }], chart.layout, GyroCharts.options);
          trimRange.max = String(Math.max(0, recorded.v.length - config.minReadings));
          trimRange.value = "0";
          markTrim(0);
          trimBox.hidden = false;
          trimRange.focus();  // keyboard users continue where the recording left them
        } else if (frame.type === "error") {
          finish(frame.message);
          socket.close();
          (startButton.disabled ? panel.querySelector(".turn") : startButton).focus();
        }
      });
      socket.addEventListener("close", () => {
        if (!saved && panel.dataset.busy === "1") finish(t("js.connection_lost"));
      });
    });
    stopButton.addEventListener("click", () => {
      if (socket && socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify({ action: "stop" }));
      stopButton.disabled = true;
    });
  }
  document.querySelectorAll('.method-panel[data-method="simulator"]').forEach(setupSimulator);

  // --- trimming a stored position's start ---------------------------------------------------
  document.querySelectorAll(".trim-form").forEach((form) => {
    const part = form.closest(".part").dataset.part;
    const select = form.querySelector(".trim-position");
    const count = form.querySelector(".trim-count");
    const status = form.querySelector(".trim-status");
    const sync = () => {
      const option = select.selectedOptions[0];
      count.value = option.dataset.trim;
      count.max = String(Math.max(0, Number(option.dataset.total) - config.minReadings));
    };
    select.addEventListener("change", sync);
    sync();
    form.querySelector(".apply-trim").addEventListener("click", async () => {
      const value = Number(count.value);
      if (count.value.trim() === "" || !Number.isInteger(value) || value < 0) {
        status.textContent = t("js.not_a_number");
        return;
      }
      try {
        await postJson("/trim", { part, position: Number(select.value), trim: value });
        status.textContent = t("js.saved");
        reloadSoon();
      } catch (error) {
        status.textContent = error.message;
      }
    });
  });

  // --- lab partners: follow the shared session live ------------------------------------------
  // Every few seconds the page asks whether the session changed (a partner saved or submitted)
  // and reloads when it did -- unless this page is in the middle of something.
  if (config.shared) {
    const note = document.getElementById("live-note");
    const busy = () => document.querySelector('[data-busy="1"]') || document.querySelector(".trim-box:not([hidden])") ||
      (document.activeElement && document.activeElement.matches("input, textarea, select") && document.activeElement.value);
    setInterval(async () => {
      if (document.hidden) return;
      try {
        const response = await fetch(`${base}/state`, { headers: { Accept: "application/json" } });
        if (!response.ok) return;
        const state = await response.json();
        if (note) {
          note.textContent = state.recording
            ? t("js.partner_recording", { part: t(`js.part_${state.recording.part}`), n: state.recording.position })
            : "";
        }
        if (state.version !== config.version && !busy()) window.location.reload();
      } catch (error) { /* offline for a moment: try again next time */ }
    }, 4000);
  }

  ["heading", "latitude"].forEach((part) => {
    if (!document.getElementById(`part-${part}`)) return;
    selectPosition(part, memory[part]?.position || 1);
    if (memory[part]?.method) showMethod(part, memory[part].method);
  });
  announceAfterReload();
})();
