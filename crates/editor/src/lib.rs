//! The browser editor (Cordonnier et al. 2018, Sections 3, 6, 8): a local web server over WebSocket, brushes, season timeline, avalanches and skiers in real time.
