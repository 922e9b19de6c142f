export function setConnection(text, bad) {
  const el = document.getElementById("conn");
  if (!el) return;
  el.textContent = text;
  el.className = bad ? "conn err" : "conn";
}

// Follows a server stream until `stopped()` says so: every item goes to `onItem`, and a
// stream that ends or fails is opened again after a pause that doubles from 0.5 s to 5 s (a
// live item resets it). `open()` is called for each attempt, so it can resume where the last
// one stopped (a request built from the last sequence seen).
export async function follow({ open, onItem, stopped, onError }) {
  let delayMs = 500;
  while (!stopped()) {
    try {
      for await (const item of open()) {
        setConnection("live", false);
        delayMs = 500;
        onItem(item);
      }
    } catch (e) {
      if (stopped()) return;
      setConnection("watch: " + e.message, true);
      onError(e);
    }
    await new Promise((r) => setTimeout(r, delayMs));
    delayMs = Math.min(delayMs * 2, 5000);
  }
}
