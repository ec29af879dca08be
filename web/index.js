// The home page: whether the server and its database answer.
import { api, badge } from './api.js';

const ready = document.getElementById('ready');
api('/readyz').then(
  () => { ready.replaceChildren(badge('active', 'ready'), ' Ready: the server and its database answer.'); },
  (error) => { ready.replaceChildren(badge('error', 'not ready'), ` Not ready: ${error.detail || error.title}`); });
