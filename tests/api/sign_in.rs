//! Signing a browser in (`/v1/sign-in`): the form, the cookie a right token sets, what
//! the cookie authorises (GET and HEAD only), the 401 page of a job's page without it,
//! and a server without a token, where nothing changes. The browser itself is in
//! `page.rs`.

use crate::helpers::{spawn_app, tiny_case, TestApp};
use crate::schema::assert_conforms;
use mpsfsi::service::Token;
use serde_json::Value;

const TOKEN: &str = "t0ken-5e1c-sign-in";

/// A client that shows redirects instead of following them.
fn client() -> reqwest::Client {
    reqwest::Client::builder()
        .redirect(reqwest::redirect::Policy::none())
        .build()
        .unwrap()
}

fn form_value(text: &str) -> String {
    text.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// POST the sign-in form with `fields` (name, value), plus `extra` headers.
async fn post_sign_in(
    app: &TestApp,
    fields: &[(&str, &str)],
    extra: &[(&str, &str)],
) -> reqwest::Response {
    let body: Vec<String> = fields
        .iter()
        .map(|(k, v)| format!("{k}={}", form_value(v)))
        .collect();
    let mut request = client()
        .post(app.url("/v1/sign-in"))
        .header("content-type", "application/x-www-form-urlencoded")
        .body(body.join("&"));
    for (k, v) in extra {
        request = request.header(*k, *v);
    }
    request.send().await.unwrap()
}

async fn submit_with_token(app: &TestApp) -> String {
    let job = app.submit_with_token(TOKEN, &tiny_case(0.002)).await;
    job["id"].as_str().unwrap().to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_right_token_sets_a_cookie_that_reads_and_only_reads() {
    let app = spawn_app("sign-in", |c| c.token = Some(Token::new(TOKEN))).await;
    let id = submit_with_token(&app).await;

    // the form, open to all, carrying `next`
    let r = client()
        .get(app.url(&format!("/v1/sign-in?next=/v1/jobs/{id}")))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 200);
    assert!(r.headers()["content-type"]
        .to_str()
        .unwrap()
        .starts_with("text/html"));
    let form = r.text().await.unwrap();
    assert!(
        form.contains("<form method=\"post\" action=\"/v1/sign-in\">"),
        "{form}"
    );
    assert!(form.contains("name=\"token\""), "{form}");
    assert!(
        form.contains(&format!("name=\"next\" value=\"/v1/jobs/{id}\"")),
        "{form}"
    );
    assert!(!form.contains("no-token"), "{form}");

    // a wrong token: the form again, 401, no cookie
    let r = post_sign_in(&app, &[("token", "not-it"), ("next", "/v1/jobs")], &[]).await;
    assert_eq!(r.status().as_u16(), 401);
    assert!(r.headers().get("set-cookie").is_none());
    let body = r.text().await.unwrap();
    assert!(
        body.contains("id=\"refused\"") && body.contains("<form"),
        "{body}"
    );

    // the right one: 303 to next, an HttpOnly, SameSite=Strict cookie that is not the token
    let next = format!("/v1/jobs/{id}");
    let r = post_sign_in(&app, &[("token", TOKEN), ("next", &next)], &[]).await;
    assert_eq!(r.status().as_u16(), 303);
    assert_eq!(r.headers()["location"], next.as_str());
    let set = r.headers()["set-cookie"].to_str().unwrap().to_string();
    for attribute in ["HttpOnly", "SameSite=Strict", "Path=/", "Max-Age=604800"] {
        assert!(set.contains(attribute), "{attribute} not in {set}");
    }
    assert!(!set.contains("Secure"), "over plain HTTP: {set}");
    assert!(!set.contains(TOKEN), "the cookie carries the token: {set}");
    let cookie = set.split(';').next().unwrap().to_string();
    assert!(cookie.starts_with("mpsfsi_read="), "{cookie}");

    // the cookie reads: JSON, the page, a picture; HEAD too
    for (path, accept) in [
        (format!("/v1/jobs/{id}"), "application/json"),
        (format!("/v1/jobs/{id}"), "text/html"),
        ("/v1/jobs".to_string(), "application/json"),
        (format!("/v1/jobs/{id}/loads.svg"), "*/*"),
    ] {
        let r = client()
            .get(app.url(&path))
            .header("cookie", &cookie)
            .header("accept", accept)
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), 200, "GET {path} ({accept})");
    }
    let r = client()
        .head(app.url(&format!("/v1/jobs/{id}")))
        .header("cookie", &cookie)
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 200, "HEAD");

    // and nothing else: a cookie-only POST, DELETE or cancel is refused with the JSON 401
    let case = serde_json::to_vec(&tiny_case(0.002)).unwrap();
    let refused = [
        client()
            .post(app.url("/v1/jobs"))
            .header("content-type", "application/json")
            .body(case),
        client().post(app.url(&format!("/v1/jobs/{id}/cancel"))),
        client().delete(app.url(&format!("/v1/jobs/{id}"))),
    ];
    for request in refused {
        let r = request.header("cookie", &cookie).send().await.unwrap();
        assert_eq!(r.status().as_u16(), 401);
        assert!(r.headers().contains_key("www-authenticate"));
        let body: Value = r.json().await.unwrap();
        assert_eq!(body["error"]["code"], "unauthorized", "{body}");
    }
    let (_, list) = {
        let r = client()
            .get(app.url("/v1/jobs"))
            .bearer_auth(TOKEN)
            .send()
            .await
            .unwrap();
        (r.status(), r.json::<Value>().await.unwrap())
    };
    assert_eq!(
        list["total"], 1,
        "the cookie-only POST submitted nothing: {list}"
    );

    // a cookie that is not the server's, altered, or expired, reads nothing
    let (expires, tag) = cookie["mpsfsi_read=".len()..].split_once('.').unwrap();
    let later: u64 = expires.parse::<u64>().unwrap() + 3600;
    let flipped = format!(
        "{}{}",
        &tag[..63],
        if tag.ends_with('0') { "1" } else { "0" }
    );
    for forged in [
        format!("mpsfsi_read={later}.{tag}"),
        format!("mpsfsi_read={expires}.{flipped}"),
        format!("mpsfsi_read={TOKEN}"),
        "mpsfsi_read=1.00".to_string(),
        format!("mpsfsi_read=1000.{tag}"),
        format!("other={}", &cookie["mpsfsi_read=".len()..]),
    ] {
        let r = client()
            .get(app.url("/v1/jobs"))
            .header("cookie", &forged)
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), 401, "{forged}");
    }
    // among other cookies, it still reads
    let r = client()
        .get(app.url("/v1/jobs"))
        .header("cookie", format!("a=b; {cookie}; c=d"))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 200);
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_page_without_a_sign_in_answers_401_with_the_sign_in_link() {
    let app = spawn_app("sign-in-page", |c| c.token = Some(Token::new(TOKEN))).await;
    let id = submit_with_token(&app).await;
    let r = client()
        .get(app.url(&format!("/v1/jobs/{id}")))
        .header("accept", "text/html,application/xhtml+xml,*/*;q=0.8")
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 401);
    assert!(r.headers().contains_key("www-authenticate"));
    assert!(r.headers()["content-type"]
        .to_str()
        .unwrap()
        .starts_with("text/html"));
    let body = r.text().await.unwrap();
    let link = format!("href=\"/v1/sign-in?next=%2Fv1%2Fjobs%2F{id}\"");
    assert!(body.contains(&link), "{link} not in {body}");

    // JSON routes keep their JSON 401, whatever the Accept header
    for (path, accept) in [
        (format!("/v1/jobs/{id}"), "application/json"),
        ("/v1/jobs".to_string(), "text/html"),
        (format!("/v1/jobs/{id}/loads"), "text/html"),
    ] {
        let r = client()
            .get(app.url(&path))
            .header("accept", accept)
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), 401, "{path}");
        let body: Value = r.json().await.unwrap();
        assert_eq!(body["error"]["code"], "unauthorized");
    }
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_cookie_is_secure_behind_tls_and_next_stays_on_the_site() {
    let app = spawn_app("sign-in-tls", |c| c.token = Some(Token::new(TOKEN))).await;
    for proxy in [
        ("x-forwarded-proto", "https"),
        ("forwarded", "for=192.0.2.60;proto=https;by=203.0.113.43"),
    ] {
        let r = post_sign_in(&app, &[("token", TOKEN)], &[proxy]).await;
        assert_eq!(r.status().as_u16(), 303);
        assert_eq!(r.headers()["location"], "/v1/jobs");
        let set = r.headers()["set-cookie"].to_str().unwrap();
        assert!(set.ends_with("; Secure"), "{proxy:?}: {set}");
    }
    let r = post_sign_in(&app, &[("token", TOKEN)], &[("x-forwarded-proto", "http")]).await;
    assert!(!r.headers()["set-cookie"]
        .to_str()
        .unwrap()
        .contains("Secure"));

    for next in [
        "https://evil.example/",
        "//evil.example/v1/",
        "/v2/jobs",
        "v1/jobs",
        "/v1/jobs with space",
        "/v1/\u{e9}",
    ] {
        let r = post_sign_in(&app, &[("token", TOKEN), ("next", next)], &[]).await;
        assert_eq!(r.status().as_u16(), 400, "{next}");
        assert!(r.headers().get("set-cookie").is_none());
        let body: Value = r.json().await.unwrap();
        assert_eq!(body["error"]["path"], "next", "{body}");
        assert_conforms("POST", "/v1/sign-in", 400, &body);
        let r = client()
            .get(app.url(&format!("/v1/sign-in?next={}", form_value(next))))
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), 400, "GET {next}");
    }
    // a form without the token, an empty one, another field or another media type: 400
    for (content_type, body) in [
        (
            "application/x-www-form-urlencoded",
            "next=%2Fv1%2Fjobs".to_string(),
        ),
        ("application/x-www-form-urlencoded", "token=".to_string()),
        (
            "application/x-www-form-urlencoded",
            format!("token={TOKEN}&x=1"),
        ),
        ("application/json", format!("{{\"token\": \"{TOKEN}\"}}")),
    ] {
        let r = client()
            .post(app.url("/v1/sign-in"))
            .header("content-type", content_type)
            .body(body.clone())
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), 400, "{content_type} {body}");
        let json: Value = r.json().await.unwrap();
        assert_conforms("POST", "/v1/sign-in", 400, &json);
    }
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn without_a_token_nothing_needs_signing_in() {
    let app = spawn_app("sign-in-none", |_| {}).await;
    let r = client().get(app.url("/v1/sign-in")).send().await.unwrap();
    assert_eq!(r.status().as_u16(), 200);
    let form = r.text().await.unwrap();
    assert!(form.contains("id=\"no-token\""), "{form}");
    let r = post_sign_in(&app, &[("token", "anything"), ("next", "/v1/health")], &[]).await;
    assert_eq!(r.status().as_u16(), 303);
    assert_eq!(r.headers()["location"], "/v1/health");
    assert!(r.headers().get("set-cookie").is_none());
    // and every route answers as before, without a cookie
    let id = app.submit(&tiny_case(0.002)).await;
    let page = app.page(&id).await;
    assert!(page.contains("<h1>"), "{page}");
    app.stop().await;
}
