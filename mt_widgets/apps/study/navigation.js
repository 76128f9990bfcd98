// The page's address, changed from the kernel: the front end of navigation.py's PageAddress.
// It acts when a view of the widget is shown (again when a page shows it again), never on its own.

function render({ model, el }) {
  el.replaceChildren();
  const address = model.get("address");
  if (model.get("action") === "go") {
    // Send the page on (a completion URL), after the delay the goodbye text needs to be read.
    const timer = setTimeout(() => window.location.assign(address), model.get("delay_ms"));
    return () => clearTimeout(timer);
  }
  // Only record where the participant is: a reload asks the server for the same page with this query.
  history.replaceState(null, "", window.location.pathname + address);
}

export default { render };
