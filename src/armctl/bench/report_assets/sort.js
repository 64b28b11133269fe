// sorting a table of the bench report by a header click; numbers by their data-key, text by its words
document.querySelectorAll("table.sortable").forEach(function(table){
  table.querySelectorAll("th").forEach(function(th, col){
    th.addEventListener("click", function(){
      const up = th.getAttribute("aria-sort") !== "ascending";
      table.querySelectorAll("th").forEach(h => h.removeAttribute("aria-sort"));
      th.setAttribute("aria-sort", up ? "ascending" : "descending");
      const body = table.tBodies[0], rows = Array.from(body.rows);
      function key(r){ const c = r.cells[col], k = c.getAttribute("data-key");
        return k === null ? null : (c.classList.contains("text") ? k : parseFloat(k)); }
      rows.sort(function(a, b){ const x = key(a), y = key(b);
        if (x === null) return 1; if (y === null) return -1;
        const d = (typeof x === "number") ? x - y : String(x).localeCompare(String(y));
        return up ? d : -d; });
      rows.forEach(r => body.appendChild(r));
    });
  });
});
