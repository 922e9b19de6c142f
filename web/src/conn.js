export function setConnection(text, bad) {
  const el = document.getElementById("conn");
  if (!el) return;
  el.textContent = text;
  el.className = bad ? "conn err" : "conn";
}
