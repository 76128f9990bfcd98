// The instruction video's player: the front end of video.py's VideoPlayer. It tells the kernel
// when the video starts ("played") and when it reaches its end ("ended"), with whether the ranges
// the browser really played (seeking skips them) cover the share of its length that counts as watched.

function render({ model, el }) {
  const video = document.createElement("video");
  video.className = "mt-video";
  video.src = model.get("src");
  video.controls = true;
  video.preload = "auto";
  video.style.maxWidth = "720px";
  video.style.width = "100%";
  video.addEventListener("play", () => model.send({ event: "played" }));
  video.addEventListener("ended", () => {
    let seconds = 0;
    for (let i = 0; i < video.played.length; i++) seconds += video.played.end(i) - video.played.start(i);
    const whole = isFinite(video.duration) && video.duration > 0
      && seconds >= model.get("watched_fraction") * video.duration;
    model.send({ event: "ended", whole });
  });
  const replay = document.createElement("button");
  replay.className = "mt-video-replay";
  replay.textContent = "Play again from the start";
  replay.addEventListener("click", () => {
    video.currentTime = 0;
    video.play();
  });
  const row = document.createElement("div");
  row.append(replay);
  el.replaceChildren(video, row);
}

export default { render };
