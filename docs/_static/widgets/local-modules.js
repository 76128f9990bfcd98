// The widgets' front-end modules from this site, not a CDN (docs/conf.py, nb_ipywidgets_js): the
// widget manager (embed-amd.js, loaded next) asks RequireJS for each model's module by name, and
// falls back to a CDN only when RequireJS cannot load it. ipycanvas and anywidget are the AMD builds
// their pip packages ship, copied beside this file at each build.
(function () {
  var here = document.currentScript.src.replace(/[^/]*$/, "");
  window.require.config({paths: {ipycanvas: here + "ipycanvas/index", anywidget: here + "anywidget/index"}});
})();
